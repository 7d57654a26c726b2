"""Pen palettes (non-negative least squares), ``torus --palette``, layered CSVs in ``evaluate``, and vpype
reading stipple's own SVG back with its layers and pen colours."""

import json
import re

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image
from scipy.optimize import nnls

from stipple.cli import main
from stipple.colour import TIE_BREAK, parse_palette, pen_coverages, separate
from stipple.errors import StippleError
from stipple.multiclass import class_counts

PENS = "#00a0e0,#e0007a,#ffe000,#000000"


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture
def flag(tmp_path):
    """Three bands: the first pen's colour, the second's, and a grey."""
    pixels = np.zeros((12, 18, 3), dtype=np.uint8)
    pixels[:, :6] = (0, 160, 224)
    pixels[:, 6:12] = (224, 0, 122)
    pixels[:, 12:] = (120, 120, 120)
    path = tmp_path / "flag.png"
    Image.fromarray(pixels).save(path)
    return path, pixels / 255.0


def test_pen_coverages_are_the_exact_nonnegative_least_squares_fit():
    pens = parse_palette(PENS)
    rgb = np.random.default_rng(3).random((9, 11, 3))
    system = np.vstack([1 - np.array([colour for _, colour in pens]).T, np.sqrt(TIE_BREAK) * np.ones((1, 4))])
    expected = np.array([nnls(system, np.r_[1 - pixel, 0.0])[0] for pixel in rgb.reshape(-1, 3)])
    expected /= np.maximum(expected.sum(axis=1, keepdims=True), 1.0)
    np.testing.assert_allclose(pen_coverages(rgb, pens).reshape(-1, 4), expected, atol=1e-9)


def test_a_pen_coloured_pixel_is_that_pen_and_grey_takes_black(flag):
    layers = {layer.name: layer.density for layer in separate(flag[1], parse_palette(PENS))}
    assert layers["#00a0e0"][:, :6] == pytest.approx(1.0, abs=2e-3) and layers["#e0007a"][:, :6].max() < 1e-3
    assert layers["#e0007a"][:, 6:12] == pytest.approx(1.0, abs=2e-3)
    grey = 1 - 120 / 255
    assert layers["#000000"][:, 12:] == pytest.approx(grey, abs=1e-3) and "#ffe000" not in layers  # no ink, no layer


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("#00a0e0,nonsense", "palette colour must be a colour"),
        ("#ffffff", "too close to the white paper"),
        ("red,red", "must differ"),
        (",".join(["black"] * 9), "1 to 8"),
    ],
)
def test_bad_palettes_are_refused_by_name(text, message):
    with pytest.raises(StippleError, match=message):
        parse_palette(text)


def test_torus_with_a_palette_writes_layers_and_resumes(flag, tmp_path):
    path, rgb = flag
    checkpoint = tmp_path / "run.npz"
    common = ["torus", path, "-M", 240, "--palette", PENS, "-q", "--checkpoint", checkpoint]
    result = run(common + ["--iterations", 5, "-o", tmp_path / "a.csv"])
    assert result.exit_code == 0, result.output
    result = run(common + ["--iterations", 12, "--resume", "-o", tmp_path / "b.csv", "-o", tmp_path / "b.svg"])
    assert result.exit_code == 0, result.output
    rows = [line.split(",") for line in (tmp_path / "b.csv").read_text().splitlines()[1:]]
    layers = separate(rgb, parse_palette(PENS))
    expected = class_counts([layer.density.sum() for layer in layers], 240)
    assert [sum(row[2] == layer.name for row in rows) for layer in layers] == expected.tolist()
    svg = (tmp_path / "b.svg").read_text()
    assert re.findall(r'inkscape:label="\d-([^"]+)"', svg) == [layer.name for layer in layers]
    other = run(["torus", path, "-M", 240, "--palette", "cmyk", "-q", "--checkpoint", checkpoint, "--resume"])
    assert other.exit_code == 1  # another separation is another problem


def test_evaluate_reports_every_ink_and_the_union(flag, tmp_path):
    path, rgb = flag
    result = run(["colour", path, "-M", 300, "--iterations", 15, "-q", "--palette", PENS, "-o", tmp_path / "d.csv"])
    assert result.exit_code == 0, result.output
    result = run(["evaluate", tmp_path / "d.csv", path, "--palette", PENS, "--json", tmp_path / "e.json"])
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "e.json").read_text())
    assert report["points"] == 300 and [item["name"] for item in report["classes"]] == PENS.split(",")[:2] + ["#000000"]
    assert all(abs(item["points"] - item["quota"]) < 1 for item in report["classes"])
    assert report["energy_ratio_to_iid"] < 0.2 and all(item["energy_ratio_to_iid"] < 0.3 for item in report["classes"])
    assert "ink #000000:" in result.output
    wrong = run(["evaluate", tmp_path / "d.csv", path])  # the cmyk inks are not these pens
    assert wrong.exit_code == 1 and "not inks of --palette cmyk" in wrong.output


def test_vpype_reads_stipples_svg_with_layers_colours_and_every_dot(flag, tmp_path):
    vpype = pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    path, _ = flag
    outputs = ["-o", tmp_path / "d.svg", "-o", tmp_path / "f.svg"]
    result = run(["colour", path, "-M", 200, "--iterations", 5, "-q", "--palette", PENS, "-o", tmp_path / "d.svg"])
    assert result.exit_code == 0, result.output
    filled = ["colour", path, "-M", 200, "--iterations", 5, "-q", "--palette", PENS, "--dot-style", "filled"]
    assert run(filled + ["-o", outputs[3]]).exit_code == 0
    for svg in (tmp_path / "d.svg", tmp_path / "f.svg"):
        # Uncropped: the tone style's discs along the page's edges are cut by the page (the torus wraps around),
        # and vpype's crop splits each such circle into pieces.
        document = vpype.read_multilayer_svg(str(svg), quantization=0.1, crop=False)
        colours = [layer.property(vpype.METADATA_FIELD_COLOR) for layer in document.layers.values()]
        # The tone style's copies of the discs across the page's edges are circles too.
        drawn = 200 + svg.read_text().count('class="copy"')
        assert len(document.layers) == 3 and sum(len(layer) for layer in document.layers.values()) == drawn
        assert colours == [vpype.Color("#00a0e0"), vpype.Color("#e0007a"), vpype.Color("#000000")], svg.name


def test_a_white_image_is_blank_in_gray_too():
    """White's luminance weights sum to 1 - 1.1e-16: --palette gray stippled an all-white image."""
    with pytest.raises(StippleError, match="blank"):
        separate(np.ones((6, 8, 3)), "gray")
    assert separate(np.full((6, 8, 3), 0.5), "gray")[0].density == pytest.approx(np.full((6, 8), 0.5))


def test_inks_that_print_none_of_the_colours_are_named_not_called_blank():
    """A yellow image with a blue pen was called "blank (all white)"."""
    yellow = np.zeros((6, 8, 3)) + [1.0, 1.0, 0.0]
    with pytest.raises(StippleError, match="the inks blue print none of the image's colours"):
        separate(yellow, parse_palette("blue"))
    with pytest.raises(StippleError, match="blank"):
        separate(np.ones((6, 8, 3)), parse_palette("blue"))
    assert [layer.name for layer in separate(yellow, parse_palette("blue,#ffff00"))] == ["#ffff00"]


@pytest.mark.parametrize("weight", [1e300, -1.0, float("nan")])
def test_union_weight_out_of_range_is_refused(weight):
    from stipple.colour import colour_problem

    with pytest.raises(StippleError, match=r"--union-weight must be a number in \[0, 1e\+06\]"):
        colour_problem(np.full((6, 8, 3), 0.5), 50, union_weight=weight)
