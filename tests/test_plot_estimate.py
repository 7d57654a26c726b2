"""The plot estimate (``stipple evaluate DRAWING.svg``) against hand-computed lengths, lifts and times, the
kinematics of constant acceleration, and (when vpype is installed) vpype's own length statistics."""

import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

from stipple.cli import main
from stipple.errors import StippleError
from stipple.io.plot_svg import read_pen_layers
from stipple.measures.plot_estimate import PlotterSettings, move_times, plot_estimate
from stipple.pipelines.outputs import torus_files


def torus_svg(points, shape, **settings):
    """The SVG that ``stipple torus`` writes of ``points`` (unit coordinates) on an image of ``shape``."""
    return torus_files(points, shape, [".svg"], settings)[".svg"]


HEAD = '<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '


def write(tmp_path, body, size='width="100mm" height="50mm" viewBox="0 0 100 50"', name="drawing.svg"):
    path = tmp_path / name
    path.write_text(f"{HEAD}{size}>{body}</svg>")
    return path


def grid_svg(tmp_path):
    """3 rows of 4 dots 10 mm apart, each a 0.5 mm stroke to the right, row by row."""
    strokes = [f'<path d="M{x},{y} L{x + 0.5},{y}"/>' for y in (10, 20, 30) for x in (10, 20, 30, 40)]
    return write(tmp_path, '<g inkscape:groupmode="layer" inkscape:label="1-dots">' + "".join(strokes) + "</g>")


def test_grid_of_dots_by_hand(tmp_path):
    estimate = plot_estimate(read_pen_layers(grid_svg(tmp_path)))
    layer = estimate.layers[0]
    hops = 9 * 9.5 + 2 * np.hypot(30.5, 10)  # 3 hops along each row, 2 from a row's end to the next row's start
    home = np.hypot(10, 10) + np.hypot(40.5, 30)
    assert (layer.name, layer.paths, layer.lifts, layer.segments) == ("1-dots", 12, 12, 12)
    assert layer.pen_down == pytest.approx(12 * 0.5, rel=1e-12)
    assert layer.pen_up == pytest.approx(hops, rel=1e-12)
    assert layer.home == pytest.approx(home, rel=1e-12)
    assert layer.time == pytest.approx(6 / 55 + (hops + home) / 165 + 12 * 0.3, rel=1e-12)


def test_settings_change_the_time_by_hand(tmp_path):
    settings = PlotterSettings(speed=10, travel_speed=100, lift=1.0)
    layer = plot_estimate(read_pen_layers(grid_svg(tmp_path)), settings).layers[0]
    assert layer.time == pytest.approx(6 / 10 + (layer.pen_up + layer.home) / 100 + 12, rel=1e-12)


def test_known_path_with_transforms_units_and_curves(tmp_path):
    # viewBox 0..50 on 10 cm: one user unit is 2 mm; the group doubles again and shifts by 5 user units.
    body = (
        '<g transform="translate(5,0) scale(2)">'
        '<path d="m0,0 10,0 v10 z M20,0 C20,5 20,5 20,10"/>'  # implicit l after m; a straight cubic
        '<path d="M40,20 A5 5 0 0 1 30,20 A5 5 0 0 1 40,20"/>'  # a full circle of radius 5 from two arcs
        "</g>"
    )
    layers = read_pen_layers(write(tmp_path, body, 'width="10cm" height="5cm" viewBox="0 0 50 25"'))
    paths = layers[0].paths
    assert len(paths) == 3
    np.testing.assert_allclose(paths[0], 4 * np.array([0, 10, 10 + 10j, 0]) + 10, atol=1e-12)
    layer = plot_estimate(layers).layers[0]
    triangle = 4 * (20 + np.hypot(10, 10))
    line = 4 * 10
    circle = 4 * 2 * np.pi * 5
    assert layer.pen_down == pytest.approx(triangle + line + circle, rel=1e-4)
    # pen up: triangle's end (10, 0) -> line's start (90, 0); line's end (90, 40) -> circle's start (170, 80)
    assert layer.pen_up == pytest.approx(80 + np.hypot(80, 40), rel=1e-12)
    assert layer.home == pytest.approx(10 + np.hypot(170, 80), rel=1e-12)


def test_two_layers_each_from_home_and_back(tmp_path):
    body = (
        '<g inkscape:groupmode="layer" inkscape:label="1-cyan"><line x1="10" y1="0" x2="10" y2="30"/></g>'
        '<g inkscape:groupmode="layer" inkscape:label="2-black">'
        '<polyline points="0,40 30,40"/><polygon points="50,0 50,10 60,10"/></g>'
    )
    estimate = plot_estimate(read_pen_layers(write(tmp_path, body)), PlotterSettings(lift=0.5))
    cyan, black = estimate.layers
    assert (cyan.name, cyan.paths, black.name, black.paths) == ("1-cyan", 1, "2-black", 2)
    assert cyan.pen_down == pytest.approx(30) and cyan.pen_up == 0 and cyan.home == pytest.approx(10 + np.hypot(10, 30))
    assert black.pen_down == pytest.approx(30 + 20 + np.hypot(10, 10))
    assert black.pen_up == pytest.approx(np.hypot(20, 40)) and black.home == pytest.approx(40 + 50)
    total = estimate.total
    assert (total.paths, total.lifts) == (3, 3)
    assert total.pen_down == pytest.approx(cyan.pen_down + black.pen_down)
    assert total.time == pytest.approx(cyan.time + black.time)
    assert total.lift_time == pytest.approx(1.5)


def test_stipple_point_drawing_is_one_short_stroke_per_dot(tmp_path, rng):
    points = rng.random((50, 2))
    svg = torus_svg(points, (40, 80), width=(160.0, "mm"), dot_style="point", pen_width=(0.3, "mm"))
    (tmp_path / "dots.svg").write_bytes(svg)
    estimate = plot_estimate(read_pen_layers(tmp_path / "dots.svg"))
    assert estimate.total.paths == 50 and estimate.total.lifts == 50
    assert estimate.total.pen_down == pytest.approx(50 * 0.03, rel=1e-3)  # a stroke a tenth of the pen long


def test_circles_have_their_perimeter(tmp_path):
    body = '<g><circle cx="20" cy="20" r="5"/><ellipse cx="60" cy="20" rx="4" ry="4"/></g>'
    layer = plot_estimate(read_pen_layers(write(tmp_path, body))).layers[0]
    assert layer.pen_down == pytest.approx(2 * np.pi * 9, rel=1e-4)


def test_shapes_of_size_zero_draw_nothing(tmp_path):
    body = '<g><circle cx="20" cy="20" r="0"/><ellipse cx="6" cy="2" rx="4" ry="0"/><rect width="0" height="5"/></g>'
    body += '<path d="M 1,1 l 3e0-4E-0 h.5"/>'  # numbers run together: 1,1 then 3,-4, then 0.5
    layer = plot_estimate(read_pen_layers(write(tmp_path, body))).layers[0]
    assert layer.paths == 1 and layer.pen_down == pytest.approx(5.5)


def profile_distance(total_time, speed, acceleration, samples=200001):
    """The distance covered in ``total_time`` by the trapezoidal speed profile v(t) = min(a t, v, a (T - t))."""
    t = np.linspace(0.0, total_time, samples)
    velocity = np.minimum(np.minimum(acceleration * t, speed), acceleration * (total_time - t))
    return np.trapezoid(velocity, t)


@pytest.mark.parametrize("length", [0.01, 1.0, 4.0, 12.5, 100.0])
def test_accelerated_moves_cover_their_length(length):
    speed, acceleration = 50.0, 200.0  # full speed is reached after 6.25 mm; 12.5 mm is the limit case
    (time,) = move_times([length], speed, acceleration)
    assert profile_distance(time, speed, acceleration) == pytest.approx(length, rel=1e-6)
    assert time >= length / speed


def test_accelerated_exact_cases():
    speed, acceleration = 50.0, 200.0
    times = move_times([12.5, 3.125, 112.5, 0.0], speed, acceleration)
    # 12.5 mm: accelerate for 0.25 s and decelerate for 0.25 s; 3.125 mm: 0.125 s each way (half the speed);
    # 112.5 mm: the same two ramps and 100 mm at full speed (2 s); nothing takes no time.
    np.testing.assert_allclose(times, [0.5, 0.25, 2.5, 0.0], rtol=1e-12)


def test_json_report_and_text(tmp_path):
    drawing = grid_svg(tmp_path)
    result = CliRunner().invoke(
        main, ["evaluate", str(drawing), "--json", "-", "--speed", "10", "--acceleration", "200"]
    )
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    assert report["total"]["lifts"] == 12 and report["settings"]["speed"] == 10
    expected = 12 * move_times([0.5], 10, 200)[0]
    assert report["total"]["draw_time"] == pytest.approx(expected, rel=1e-12)
    text = CliRunner().invoke(main, ["evaluate", str(drawing)])
    assert text.exit_code == 0 and "1-dots" in text.output and "lifts" in text.output


@pytest.mark.parametrize(
    "body, message",
    [
        ('<!DOCTYPE svg [<!ENTITY a "aaaa">]><svg xmlns="http://www.w3.org/2000/svg">&a;</svg>', "entities"),
        ("<svg", "not a readable SVG"),
        ("<html></html>", "not an SVG"),
        ('<svg xmlns="http://www.w3.org/2000/svg"><path d="10,10 L 20"/></svg>', "path data"),
        ('<svg xmlns="http://www.w3.org/2000/svg" width="wide" viewBox="0 0 1 1"/>', "length"),
        # A hostile sweep: "nan" was read as an arc command "a", and a negative radius drew a circle.
        ('<svg xmlns="http://www.w3.org/2000/svg"><path d="M 1 1 L nan 50"/></svg>', "'nan' is neither a command"),
        ('<svg xmlns="http://www.w3.org/2000/svg"><circle cx="5" cy="5" r="-1"/></svg>', "r='-1'> is negative"),
        # Python's float() reads other scripts' digits; SVG's numbers are ASCII.
        ('<svg xmlns="http://www.w3.org/2000/svg"><path d="M1 1L\u0663 5"/></svg>', "'\u0663' is neither a command"),
        ('<svg xmlns="http://www.w3.org/2000/svg"><rect width="-3" height="2"/></svg>', "width='-3'> is negative"),
    ],
)
def test_bad_drawings_get_one_line(tmp_path, body, message):
    path = tmp_path / "bad.svg"
    path.write_text(body)
    result = CliRunner().invoke(main, ["evaluate", str(path)])
    assert result.exit_code != 0 and message in result.output
    assert "Traceback" not in result.output and len(result.output.strip().splitlines()) == 1


@pytest.mark.parametrize("option", ["--speed=0", "--travel-speed=-1", "--lift=nan", "--acceleration=inf"])
def test_bad_settings_are_named(tmp_path, option):
    result = CliRunner().invoke(main, ["evaluate", str(grid_svg(tmp_path)), option])
    name = option.split("=")[0]
    assert result.exit_code != 0 and name in result.output and "Traceback" not in result.output


def test_matches_vpype_lengths(tmp_path, rng):
    vp = pytest.importorskip("vpype")
    drawings = []
    for style, count in (("point", 120), ("circle", 80), ("filled", 40)):
        svg = torus_svg(rng.random((count, 2)), (60, 90), width=(150.0, "mm"), dot_style=style)
        drawings.append(tmp_path / f"{style}.svg")
        drawings[-1].write_bytes(svg)
    for path in drawings:
        document = vp.read_multilayer_svg(str(path), quantization=0.1)
        ours = plot_estimate(read_pen_layers(path)).total
        millimetre = 96 / 25.4
        assert ours.pen_down * millimetre == pytest.approx(document.length(), rel=1e-3)
        assert ours.pen_up * millimetre == pytest.approx(document.pen_up_length(), rel=1e-3)
        assert ours.paths == sum(len(layer) for layer in document.layers.values())


def test_a_plain_doctype_is_read(tmp_path):
    path = tmp_path / "old.svg"
    path.write_text(
        '<?xml version="1.0"?>\n<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" '
        '"http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd">\n'
        '<svg xmlns="http://www.w3.org/2000/svg" width="96px" height="96px"><line x1="0" y1="0" x2="96" y2="0"/></svg>'
    )
    estimate = plot_estimate(read_pen_layers(path))
    assert estimate.total.pen_down == pytest.approx(25.4) and estimate.layers[0].name == "(outside layers)"


def test_svgs_that_vpype_writes(tmp_path):
    vp = pytest.importorskip("vpype")
    import vpype_cli

    path = tmp_path / "vpype.svg"
    vpype_cli.execute(
        f"rect -l 1 10mm 10mm 30mm 20mm circle -l 2 60mm 40mm 15mm line -l 2 0 0 5cm 5cm translate 1cm 1cm write {path}"
    )
    # vpype crops to the page when reading (the circle overhangs it); a plotter draws what the file holds
    document = vp.read_multilayer_svg(str(path), quantization=0.1, crop=False)
    estimate = plot_estimate(read_pen_layers(path))
    assert [layer.paths for layer in estimate.layers] == [len(layer) for layer in document.layers.values()]
    millimetre = 96 / 25.4
    for ours, theirs in zip(estimate.layers, document.layers.values(), strict=True):
        assert ours.pen_down * millimetre == pytest.approx(theirs.length(), rel=1e-3)
        assert ours.pen_up * millimetre == pytest.approx(theirs.pen_up_length()[0], abs=1e-6, rel=1e-3)
    assert estimate.layers[0].pen_down == pytest.approx(2 * (30 + 20), rel=1e-6)


@pytest.mark.parametrize(
    "settings, message",
    [
        ({"speed": 1e-300}, "--speed must be a speed in [0.01, 100000] mm/s"),
        ({"travel_speed": float("inf")}, "--travel-speed must be a speed"),
        ({"lift": 1e9}, "--lift must be a time in [0, 60] s"),
        ({"acceleration": 0.0}, "--acceleration must be in"),
    ],
)
def test_plotter_settings_out_of_a_plotters_range_are_refused(settings, message):
    """--speed 1e-300 printed a plot time of about 300 digits of hours."""
    with pytest.raises(StippleError, match=re.escape(message)):
        PlotterSettings(**settings)
