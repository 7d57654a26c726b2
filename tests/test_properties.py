"""Property-based tests: loaders and option parsers either succeed with valid values or raise StippleError."""

import io

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from stipple.cli.supervise import parse_every
from stipple.cli.views import parse_view
from stipple.errors import StippleError
from stipple.io.images import NPY_MAGIC, load_density
from stipple.io.points import csv_bytes, read_points_csv
from stipple.io.units import UNITS, parse_length

FAST = settings(max_examples=150, deadline=None, derandomize=True)
SHAPES = st.tuples(st.integers(0, 5), st.integers(0, 5)) | st.tuples(st.integers(1, 3))


def bytes_source(data, name="input"):
    stream = io.BytesIO(data)
    stream.name = name
    return stream


@FAST
@given(st.binary(max_size=400))
def test_arbitrary_bytes_load_or_fail_cleanly(data):
    try:
        density = load_density(bytes_source(data))
    except StippleError:
        return
    assert density.ndim == 2 and np.all((density >= 0) & (density <= 1))


@FAST
@given(st.binary(max_size=300))
def test_arbitrary_npy_payloads_fail_cleanly(tail):
    try:
        load_density(bytes_source(NPY_MAGIC + tail))
    except StippleError:
        return


@FAST
@given(
    st.one_of(
        arrays(np.float64, SHAPES, elements=st.floats(allow_nan=True, allow_infinity=True)),
        arrays(np.int16, SHAPES),
        arrays(np.bool_, SHAPES),
    )
)
def test_numeric_arrays_load_or_fail_cleanly(array):
    """Includes values near the float64 limits, where a naive max - min overflows."""
    buffer = io.BytesIO()
    np.save(buffer, array)
    try:
        density = load_density(bytes_source(buffer.getvalue()))
    except StippleError:
        return
    assert density.shape == array.shape and np.all((density >= 0) & (density <= 1))
    assert np.isclose(density.min(), 0) and np.isclose(density.max(), 1)


@FAST
@given(st.text(max_size=20))
def test_parse_length(text):
    try:
        value, unit = parse_length(text)
    except StippleError:
        return
    assert value > 0 and unit in UNITS


@FAST
@given(st.floats(1e-2, 1e4), st.sampled_from(["mm", "cm", "in", "pt", "px", ""]))
def test_parse_length_round_trip(value, unit):
    parsed = parse_length(f"{value!r}{unit}")
    assert parsed == (value, unit or "mm")


@FAST
@given(st.text(max_size=12))
def test_parse_every(text):
    try:
        seconds, iterations = parse_every(text)
    except StippleError:
        return
    assert (seconds is None) != (iterations is None)
    assert (seconds or iterations) > 0


@FAST
@given(st.text(max_size=16))
def test_parse_view(text):
    try:
        lon, lat = parse_view(text)
    except StippleError:
        return
    assert -90 <= lat <= 90 and np.isfinite(lon)


@FAST
@given(st.text(max_size=200))
def test_points_csv(text):
    try:
        points = read_points_csv(bytes_source(text.encode()), ("x", "y"))
    except StippleError:
        return
    assert points.shape[1] == 2 and len(points) > 0 and np.all(np.isfinite(points))


@FAST
@given(arrays(np.float64, st.tuples(st.integers(0, 30), st.just(3)), elements=st.floats(-1e300, 1e300)))
def test_a_points_csv_writes_every_value_in_its_format_and_reads_back(table):
    """Each value as ``format(value, number_format)`` in its row (the writer's one call per row must not change a
    byte), and the 17-digit table reads back exactly."""
    for number_format in (".6f", ".17g"):
        data = csv_bytes(list(table.T), ["x", "y", "z"], number_format)
        rows = ["x,y,z", *(",".join(format(value, number_format) for value in row) for row in table)]
        assert data == ("\n".join(rows) + "\n").encode()
    if len(table):
        back = read_points_csv(bytes_source(csv_bytes(list(table.T), ["x", "y", "z"], ".17g")), ("x", "y", "z"))
        np.testing.assert_array_equal(back, table)


def test_extreme_values_rescale_without_overflow():
    buffer = io.BytesIO()
    np.save(buffer, np.array([[-1.7e308, 0.0], [1.7e308, 1.0]]))
    density = load_density(bytes_source(buffer.getvalue()))
    np.testing.assert_allclose(density, [[0, 0.5], [1, 0.5]])


def test_a_pen_in_points_is_a_72nd_of_an_inch():
    """Pen widths are often given in points (a 0.7 pt liner); ``pt`` was refused."""
    assert parse_length("0.7pt") == (0.7, "pt")
    assert abs(72 * UNITS["pt"] - UNITS["in"]) < 1e-12
