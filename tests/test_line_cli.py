"""``stipple line``: outputs, evaluation of a line, checkpoints and bad input."""

import re

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main


@pytest.fixture
def ramp_path(tmp_path):
    ramp = np.tile(np.linspace(0, 255, 48, dtype=np.uint8), (32, 1))
    path = tmp_path / "ramp.png"
    Image.fromarray(ramp).save(path)
    return path


def run(args, **kwargs):
    return CliRunner().invoke(main, [str(a) for a in args], **kwargs)


def test_line_writes_one_closed_path_as_csv_svg_png(ramp_path, tmp_path):
    outputs = [tmp_path / name for name in ("line.csv", "line.svg", "line.png")]
    args = ["line", ramp_path, "-M", 400, "--iterations", 60, "-q", "--pen-width", "0.5mm"]
    result = run(args + [item for path in outputs for item in ("-o", path)])
    assert result.exit_code == 0, result.output
    assert outputs[0].read_text().startswith("x,y\n")
    table = np.loadtxt(outputs[0], delimiter=",", skiprows=1)
    assert table.shape == (400, 2)
    assert np.all((table >= 0) & (table <= [48, 32]))
    segments = np.linalg.norm(np.roll(table, -1, axis=0) - table, axis=1)
    assert segments.max() / segments.mean() <= 1.05
    assert np.sum(table[:, 0] < 24) > 2 * np.sum(table[:, 0] >= 24)  # the line is denser where the ramp is dark
    svg = outputs[1].read_text()
    assert svg.count("<path") == 1 and svg.count(" Z") == 1 and 'fill="none"' in svg
    path = re.search(r'd="M ([^"]*) Z"', svg).group(1)
    vertices = np.array([[float(v) for v in pair.split(",")] for pair in path.split()])
    # Drawn at least half the stroke from the page's edges (no stroke past the page), elsewhere where they are.
    np.testing.assert_allclose(vertices, np.clip(table, 0.06, [48 - 0.06, 32 - 0.06]), atol=2e-3)
    assert 'stroke-width="0.1200"' in svg  # 0.5 mm of a 200 mm wide drawing of 48 px
    picture = np.asarray(Image.open(outputs[2]))
    assert picture.shape == (128, 192) and picture.min() < 128 and picture.max() == 255


def test_an_inverted_line_is_drawn_white_on_black(ramp_path, tmp_path):
    """``--invert`` puts the line on the light parts and draws it white on black, so the picture follows the
    image's tones (it was stroked black on white: the negative)."""
    png, svg = tmp_path / "line.png", tmp_path / "line.svg"
    result = run(["line", ramp_path, "--invert", "-M", 400, "--iterations", 60, "-q", "-o", png, "-o", svg])
    assert result.exit_code == 0, result.output
    drawn = np.asarray(Image.open(png).convert("L"), dtype=float) / 255
    quarters = [drawn[:, k * drawn.shape[1] // 4 : (k + 1) * drawn.shape[1] // 4].mean() for k in range(4)]
    assert np.all(np.diff(quarters) > 0.02), quarters  # light where the ramp is light
    assert quarters[0] < 0.15
    text = svg.read_text()
    assert 'fill="#000000"' in text and 'stroke="#ffffff"' in text


def test_the_default_stroke_draws_the_image_tone(ramp_path, tmp_path):
    """Without --pen-width the stroke is the one whose ink covers the image's mean darkness: the drawing's tone
    follows the ramp's (a 1-pixel stroke drew a 3:1 photo at 0.29 too light on average)."""
    png = tmp_path / "line.png"
    result = run(["line", ramp_path, "-M", 600, "--iterations", 80, "-q", "-o", png])
    assert result.exit_code == 0, result.output
    drawn = 1 - np.asarray(Image.open(png).convert("L"), dtype=float) / 255
    darkness = 1 - np.asarray(Image.open(ramp_path), dtype=float) / 255
    assert abs(drawn.mean() - darkness.mean()) < 0.04, (drawn.mean(), darkness.mean())
    columns = drawn.shape[1]
    middle = [drawn[:, k * columns // 4 : (k + 1) * columns // 4].mean() for k in (1, 2)]
    wanted = [darkness[:, k * 12 : (k + 1) * 12].mean() for k in (1, 2)]
    assert np.allclose(middle, wanted, atol=0.08), (middle, wanted)


def test_evaluate_a_line(ramp_path, tmp_path):
    csv = tmp_path / "line.csv"
    assert run(["line", ramp_path, "-M", 300, "--iterations", 40, "-q", "-o", csv]).exit_code == 0
    result = run(["evaluate", "--line", csv, ramp_path])
    assert result.exit_code == 0, result.output
    assert "E_N:" in result.output and "length pixels:" in result.output
    assert re.search(r"blur sigma 2 px: PSNR [0-9.]+ dB", result.output)
    assert "max over mean segment: 1.0" in result.output


def test_evaluate_measures_the_vertices_own_measure_of_any_line(ramp_path, tmp_path):
    # The vertices' equal-weight measure carries the image's mass, so that E_N of i.i.d. points is positive;
    # before, the run's K nodes per segment gave the vertices 1/K of it, a negative expectation, and a line
    # shorter than `stipple line` allows was refused for its --length.
    from stipple.measures.reports import evaluate_line_points

    for corners in ([[10, 10], [15, 10], [15, 15], [10, 15]], [[2, 2], [46, 2], [46, 30], [2, 30]]):
        pixels = np.array(corners, dtype=float)
        report = evaluate_line_points(pixels, "torus", ramp_path, None, {"invert": False, "gamma": 1.0, "levels": None})
        assert report["expected_iid_energy"] > 0 and report["energy"] > 0
        assert np.isclose(report["length_pixels"], 2 * np.ptp(pixels, axis=0).sum())
    csv = tmp_path / "square.csv"
    np.savetxt(csv, [[10, 10], [15, 10], [15, 15], [10, 15]], delimiter=",", header="x,y", comments="")
    result = run(["evaluate", "--line", csv, ramp_path])
    assert result.exit_code == 0, result.output
    assert float(re.search(r"ratio to i.i.d.: ([-0-9.e+]+)", result.output).group(1)) > 0
    np.savetxt(csv, [[20, 20]] * 8, delimiter=",", header="x,y", comments="")
    result = run(["evaluate", "--line", csv, ramp_path])
    assert result.exit_code == 1 and "the line has length 0: all its vertices are at one place" in result.output


def test_a_line_from_vertices_at_one_place_is_parted_into_a_loop(ramp_path, tmp_path):
    start, out = tmp_path / "start.csv", tmp_path / "line.csv"
    np.savetxt(start, [[20, 20]] * 8, delimiter=",", header="x,y", comments="")
    result = run(["line", ramp_path, "-M", 8, "--init", start, "--iterations", 20, "-q", "-o", out])
    assert result.exit_code == 0, result.output
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    assert len(np.unique(table, axis=0)) == 8
    assert np.linalg.norm(np.roll(table, -1, axis=0) - table, axis=1).min() > 1.0


def test_line_resumes_from_its_checkpoint(ramp_path, tmp_path):
    checkpoint, first, second = tmp_path / "run.npz", tmp_path / "a.csv", tmp_path / "b.csv"
    args = ["line", ramp_path, "-M", 200, "-q", "--checkpoint", checkpoint]
    assert run(args + ["--iterations", 10, "-o", first]).exit_code == 0
    refused = run(args + ["--iterations", 20, "-o", second])
    assert refused.exit_code == 1 and "checkpoint exists" in refused.output
    resumed = run(args + ["--iterations", 40, "--resume", "-o", second])
    assert resumed.exit_code == 0, resumed.output
    assert not np.array_equal(
        np.loadtxt(first, delimiter=",", skiprows=1), np.loadtxt(second, delimiter=",", skiprows=1)
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-M", 3], "at least 4 vertices"),
        (["-M", 100, "--length", -5], "--length must be in [16, "),
        (["-M", 100, "-o", "x.geojson"], "GeoJSON output is for sphere points"),
        (["-M", 100, "--epsilon", 0], "epsilon must be"),
        (["-M", 100, "--init", "square.csv"], "--init square.csv: 4 vertices, but -M is 100"),
        (["-M", 4, "--init", "square.csv"], "vertices must lie in the image, 0..48 by 0..32 pixels"),
    ],
)
def test_line_bad_input(ramp_path, tmp_path, args, message, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "square.csv").write_text("x,y\n2,2\n60,2\n40,20\n2,20\n")
    result = run(["line", ramp_path, "--iterations", 2, "-q"] + args)
    assert result.exit_code == 1 and message in result.output, result.output


def test_a_line_png_too_large_to_draw_is_refused_before_the_run(tmp_path):
    """``stipple line`` checked no PNG size: a 3 x 2000 image drawn 32768 pixels wide (a 32768 x 21845333 PNG)
    ran the whole optimisation and was then killed for memory while drawing. Now it is refused at once, in one
    line, and writes nothing."""
    path = tmp_path / "tall.png"
    Image.fromarray(np.full((2000, 3), 100, dtype=np.uint8)).save(path)
    out = tmp_path / "x.png"
    result = run(["line", path, "-M", 200, "--png-width", 32768, "-q", "-o", out, "-o", tmp_path / "x.csv"])
    assert result.exit_code == 1 and "more than 262144 per side" in result.output, result.output
    assert len(result.output.strip().splitlines()) == 1
    assert not out.exists() and not (tmp_path / "x.csv").exists()


def test_vpype_reads_the_line_svg_as_one_closed_pen_path(ramp_path, tmp_path):
    """The SVG a plotter gets: one layer, one closed path through the CSV's vertices in physical units, one pen."""
    vpype = pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    csv, svg = tmp_path / "line.csv", tmp_path / "line.svg"
    args = ["line", ramp_path, "-M", 300, "--iterations", 40, "-q", "--width", "120mm", "--pen-width", "0.4mm"]
    assert run(args + ["-o", csv, "-o", svg]).exit_code == 0
    document = vpype.read_multilayer_svg(str(svg), quantization=0.01)
    (layer,) = document.layers.values()
    (path,) = layer
    millimetre = vpype.convert_length("1mm")
    assert layer.property(vpype.METADATA_FIELD_PEN_WIDTH) == pytest.approx(0.4 * millimetre, rel=1e-3)
    assert document.page_size == pytest.approx((120 * millimetre, 80 * millimetre), rel=1e-4)
    table = np.loadtxt(csv, delimiter=",", skiprows=1) * (120 * millimetre / 48)
    assert len(path) == 301 and path[0] == path[-1]
    np.testing.assert_allclose(np.column_stack([path.real, path.imag])[:-1], table, atol=0.02)


def test_vpype_stippleline_adds_one_closed_line_in_page_units(ramp_path):
    vpype = pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import vpype_cli

    document = vpype_cli.execute(f"stippleline -M 300 --iterations 40 --width 96mm --pen-width 0.5mm {ramp_path}")
    (layer,) = document.layers.values()
    (path,) = layer
    millimetre = vpype.convert_length("1mm")
    assert layer.property(vpype.METADATA_FIELD_NAME) == "line"
    assert layer.property(vpype.METADATA_FIELD_PEN_WIDTH) == pytest.approx(0.5 * millimetre)
    assert document.page_size == pytest.approx((96 * millimetre, 64 * millimetre))
    assert len(path) == 301 and path[0] == path[-1]
    half = 0.25 * millimetre  # no stroke past the page
    assert path.real.min() >= half and path.real.max() <= 96 * millimetre - half
    assert path.imag.min() >= half and path.imag.max() <= 64 * millimetre - half
    segments = np.abs(np.diff(path))
    assert segments.max() <= 1.05 * segments.mean()
    assert np.sum(path.real < 48 * millimetre) > 2 * np.sum(path.real >= 48 * millimetre)  # dark on the left


@pytest.mark.parametrize("penalty", [0, -1.0, "NaN"])
def test_a_checkpoint_with_a_bad_penalty_is_refused_in_one_line(ramp_path, tmp_path, penalty):
    """The phase count taken from the saved penalty weight (its logarithm) raised a math domain error; before it,
    a penalty of 0 ran silently (a code review)."""
    import json
    import zipfile

    checkpoint = tmp_path / "run.npz"
    args = [
        "line",
        ramp_path,
        "-M",
        200,
        "-q",
        "--iterations",
        10,
        "--checkpoint",
        checkpoint,
        "-o",
        tmp_path / "a.csv",
    ]
    assert run(args).exit_code == 0
    with zipfile.ZipFile(checkpoint) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    metadata = json.loads(str(np.load(checkpoint)["metadata"]))
    metadata["settings"]["penalty"] = float(penalty) if penalty != "NaN" else float("nan")
    buffer = tmp_path / "metadata.npy"
    np.save(buffer, np.asarray(json.dumps(metadata)))
    members["metadata.npy"] = buffer.read_bytes()
    with zipfile.ZipFile(checkpoint, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    result = run([*args, "--resume"])
    assert result.exit_code == 1 and "corrupt checkpoint metadata (penalty" in result.output, result.output
    assert "Traceback" not in result.output


@pytest.mark.parametrize("pen_width", [(0.5, "mm"), None])
def test_no_stroke_inks_past_the_page(pen_width):
    """The run's vertices rest on the image's edges, and the SVG drew their strokes up to half a stroke past the
    page (a plotter draws there; a held-out review). Vertices nearer an edge than half the stroke are drawn that
    far from it; the others where they are."""
    from stipple.render.flat import line_drawing

    rng = np.random.default_rng(3)
    points = np.concatenate([rng.random((200, 2)), [[0.0, 0.0], [1.0, 0.5], [0.3, 1.0], [0.0, 0.7]]])
    shape = (48, 64)
    drawing = line_drawing(points, shape, width=(64.0, "mm"), pen_width=pen_width, ink=0.3)
    half = drawing.stroke / 2
    assert half > 0.05
    assert drawing.line.min() >= half - 1e-12
    assert np.all(drawing.line <= np.array([64, 48]) - half + 1e-12)
    pixels = points * [64, 48]
    inside = np.all((pixels > half) & (pixels < np.array([64, 48]) - half), axis=1)
    assert inside.sum() > 150 and np.array_equal(drawing.line[inside], pixels[inside])


def test_vpype_stippleline_keeps_the_pen_on_the_page(ramp_path, monkeypatch):
    """A vertex on the image's edge is drawn half the pen from it, as ``stipple line`` draws it."""
    pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import types

    import stipple.line
    from stipple.vpype_plugin import line_path

    corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 0.5]])
    monkeypatch.setattr(stipple.line, "draw_line", lambda *args, **options: types.SimpleNamespace(points=corners))
    monkeypatch.setattr(stipple.line, "line_points", lambda points: points)
    path, height = line_path(ramp_path, 4, width=96.0, pen_width=2.0)
    assert height == pytest.approx(64.0)
    np.testing.assert_allclose(path, [1 + 1j, 95 + 1j, 95 + 63j, 48 + 32j, 1 + 1j])


def test_a_pen_too_wide_for_the_page_is_refused_for_a_line_as_for_dots():
    """A 150 mm pen on a 200 mm page: the vertices were clamped onto the page's middle line (a code review)."""
    from stipple.errors import StippleError
    from stipple.render.flat import line_drawing

    points = np.random.default_rng(3).random((50, 2))
    with pytest.raises(StippleError, match="the pen is too wide for the page: its strokes ink"):
        line_drawing(points, (32, 48), width=(200.0, "mm"), pen_width=(150.0, "mm"))


def test_a_thin_pen_draws_a_bounded_number_of_discs():
    """The discs along a line were an eighth of the pen apart whatever the pen: a 0.001 mm pen's 300 vertices
    took 2.5 GB (a code review). Half a fine pixel apart at least."""
    from stipple.io.png import stroke_centres

    path = np.array([0, 10, 10 + 10j, 10j, 0])  # 40 units long
    assert len(stroke_centres([path], 1e-6, least_spacing=0.1)) == 4 * (100 + 1)
    assert len(stroke_centres([path], 1.6, least_spacing=0.1)) == 4 * (50 + 1)  # an eighth of the pen


def test_a_dark_strip_a_few_pixels_high_keeps_its_tone_stroke():
    """Without a pen the tone stroke of a dark strip 6 px high is wider than a quarter of it: it was refused as a
    pen too wide for the page (a pen no one gave); its margin is capped at a quarter of the side instead."""
    from stipple.render.flat import line_drawing

    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    points = np.column_stack([0.5 + 0.45 * np.cos(t), 0.5 + 0.45 * np.sin(2 * t)])
    drawing = line_drawing(points, (6, 40), ink=0.95)
    half = min(drawing.stroke / 2, 1.5)  # half the stroke, at most a quarter of the strip's 6 px
    assert drawing.stroke > 3 and drawing.line.min() >= half - 1e-12 and drawing.line[:, 1].max() <= 6 - half + 1e-12
