import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main
from stipple.render.pen import greedy_order, path_length, plotter_order
from stipple.tours import two_opt

ROOT = Path(__file__).resolve().parents[1]


def run(args, **kwargs):
    return CliRunner().invoke(main, [str(a) for a in args], **kwargs)


@pytest.fixture
def torus_csv(tmp_path):
    image = tmp_path / "ramp.png"
    Image.fromarray(np.tile(np.arange(0, 240, 10, dtype=np.uint8), (16, 1))).save(image)
    points = tmp_path / "dots.csv"
    assert run(["torus", image, "-M", 300, "-N", 24, "--iterations", 10, "-q", "-o", points]).exit_code == 0
    return image, points


def test_render_reproduces_the_run_outputs(torus_csv, tmp_path):
    image, points = torus_csv
    direct = tmp_path / "direct.svg"
    run(["torus", image, "-M", 300, "-N", 24, "--iterations", 10, "-q", "-o", direct])
    rendered = tmp_path / "rendered.svg"
    result = run(["render", points, "--like", image, "-o", rendered, "-o", tmp_path / "r.png"])
    assert result.exit_code == 0, result.output

    def circles(path):
        import re

        return np.array(re.findall(r'cx="([-0-9.]+)" cy="([-0-9.]+)" r="([-0-9.]+)"', path.read_text()), dtype=float)

    np.testing.assert_allclose(circles(rendered), circles(direct), atol=2e-4)
    assert Image.open(tmp_path / "r.png").size == (1024, 683)


def test_render_from_stdin_with_size(torus_csv):
    _, points = torus_csv
    result = run(["render", "-", "--size", "24,16", "-o", "-"], input=points.read_text())
    assert result.exit_code == 0 and result.stdout == points.read_text()


def test_render_sphere_points(tmp_path):
    points = tmp_path / "globe.csv"
    run(["sphere", "builtin:gaussians", "-M", 100, "-N", 8, "--iterations", 3, "-q", "-o", points])
    result = run(
        ["render", points, "-o", tmp_path / "g.geojson", "-o", tmp_path / "g.svg", "--coords", "xyz", "-o", "-"]
    )
    assert result.exit_code == 0, result.output
    xyz = np.loadtxt(result.stdout.splitlines()[1:], delimiter=",")
    np.testing.assert_allclose(np.linalg.norm(xyz, axis=1), 1, atol=1e-6)
    assert '"MultiPoint"' in (tmp_path / "g.geojson").read_text()
    # A map's tone is not drawn again: --like was taken and ignored.
    np.save(tmp_path / "map.npy", np.ones((8, 16)))
    for option in (["--like", tmp_path / "map.npy"], ["--size", "16,8"]):
        refused = run(["render", points, "-o", tmp_path / "x.png", *option])
        assert refused.exit_code == 1 and "for torus points" in refused.output and not (tmp_path / "x.png").exists()


def circle_table(path):
    """``(layer label, fill, cx, cy, r)`` of every circle of an SVG, in document order."""
    import re

    rows = []
    for head, body in re.findall(r"(<g [^>]*>)(.*?)</g>", path.read_text(), flags=re.S):
        label, fill = re.search(r'inkscape:label="([^"]*)"', head).group(1), re.search(r'fill="([^"]*)"', head).group(1)
        for cx, cy, r in re.findall(r'cx="([-0-9.]+)" cy="([-0-9.]+)" r="([-0-9.]+)"', body):
            rows.append((label, fill, float(cx), float(cy), float(r)))
    return rows


@pytest.mark.parametrize(
    "run_options, render_options",
    [([], []), (["--palette", "cmy"], []), (["--black", "0.3"], ["--black", "0.3"])],
    ids=["cmyk", "cmy-from-the-names", "black"],
)
def test_render_of_a_colour_run_redraws_its_inks(tmp_path, run_options, render_options):
    """A layered CSV's dots keep their inks: with --like the colour image, the same layers, colours and
    tone-true radii as the colour command's own SVG, and its PNG; without, each layer in its ink's colour (they
    were drawn as one black layer). Three colour inks are a cmy separation (they were taken for cmyk, whose gray
    goes to a black ink they do not have: a far lighter picture), and --black is the run's."""
    pixels = np.zeros((12, 16, 3), dtype=np.uint8)
    pixels[:, :8], pixels[:, 8:] = (230, 40, 40), (40, 110, 110)
    image = tmp_path / "flag.png"
    Image.fromarray(pixels).save(image)
    own = [tmp_path / name for name in ("dots.csv", "dots.svg", "dots.png")]
    arguments = ["colour", image, "-M", 300, "--iterations", 15, "-q", "--png-width", 160, *run_options]
    assert run(arguments + [item for path in own for item in ("-o", path)]).exit_code == 0
    again = [tmp_path / name for name in ("again.svg", "again.png")]
    result = run(
        ["render", own[0], "--like", image, "--png-width", 160, "-o", again[0], "-o", again[1], *render_options]
    )
    assert result.exit_code == 0, result.output
    first, second = circle_table(own[1]), circle_table(again[0])
    assert [row[:2] for row in first] == [row[:2] for row in second]
    # The CSV's rounded centres move a cell's edge across a fine pixel here and there: 0.2 % in a radius.
    np.testing.assert_allclose([row[2:] for row in first], [row[2:] for row in second], rtol=3e-3, atol=2e-4)
    difference = np.abs(np.asarray(Image.open(own[2]), float) - np.asarray(Image.open(again[1]), float))
    assert difference.mean() < 1.0
    if run_options:
        return
    plain = tmp_path / "plain.svg"
    assert run(["render", own[0], "-o", plain]).exit_code == 0
    fills = {label.split("-", 1)[1]: fill for label, fill, *_ in circle_table(plain)}
    assert fills == {"cyan": "#00ffff", "magenta": "#ff00ff", "yellow": "#ffff00", "black": "#000000"}
    for options in (["--palette", "cmy"], ["--black", "0.5"]):
        refused = run(["render", own[0], "-o", tmp_path / "x.svg", *options])
        assert refused.exit_code == 1 and "give --like" in refused.output


def test_render_warns_when_points_lie_outside_the_canvas_given(torus_csv, tmp_path):
    """Points made for another image are wrapped onto the canvas of --size or --like: drawn, with a warning."""
    image, points = torus_csv
    smaller = run(["render", points, "--size", "12,8", "-o", tmp_path / "x.svg"])
    assert smaller.exit_code == 0 and "points lie outside the 12×8 image" in smaller.output
    same = run(["render", points, "--like", image, "-o", tmp_path / "y.svg"])
    assert same.exit_code == 0 and "outside" not in same.output
    both = run(["render", points, "--like", image, "--size", "12,8", "-o", tmp_path / "z.svg"])  # --size was ignored
    assert both.exit_code == 1 and "give --like or --size, not both" in both.output


def test_render_refuses_a_video_csv_of_several_frames_and_draws_one_frame(tmp_path):
    """A video's CSV holds every frame's dots: refused in one line that names its frames and how to keep one; the
    command it gives makes a file that renders."""
    import shlex

    frames = tmp_path / "video.csv"
    frames.write_text("frame,x,y\n3,1.5,2.5\n3,4.0,5.0\n4,1.6,2.5\n4,4.1,5.0\n")
    result = run(["render", frames, "-o", tmp_path / "x.svg"])
    assert result.exit_code == 1 and "a video's dots of 2 frames (3 to 4)" in result.output
    assert "Traceback" not in result.output
    advice = result.output.split("e.g. ", 1)[1].strip()
    subprocess.run(advice, shell=True, check=True, cwd=tmp_path)
    kept = tmp_path / "frame3.csv"
    assert run(["render", kept, "-o", tmp_path / "y.csv"]).exit_code == 0
    assert (tmp_path / "y.csv").read_text().count("\n") == 3 and shlex.split(advice)[0] == "awk"
    # The advice works for a name with a space (quoted) and for standard input (piped again).
    spaced = tmp_path / "my video.csv"
    spaced.write_text(frames.read_text().replace("\n3,", "\n1234567,").replace("\n4,", "\n1234568,"))
    result = run(["render", spaced, "-o", tmp_path / "x.svg"])
    assert "(1234567 to 1234568)" in result.output
    subprocess.run(result.output.split("e.g. ", 1)[1].strip(), shell=True, check=True, cwd=tmp_path)
    assert (tmp_path / "frame1234567.csv").read_text().count("\n") == 3
    result = run(["render", "-", "-o", tmp_path / "x.svg"], input=frames.read_text())
    advice = result.output.split("e.g. ", 1)[1].strip()
    subprocess.run(advice, shell=True, check=True, cwd=tmp_path, input=frames.read_text(), text=True)
    assert (tmp_path / "frame3.csv").read_text() == "frame,x,y\n3,1.5,2.5\n3,4.0,5.0\n"


def test_render_rejects_unknown_csv(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n")
    result = run(["render", bad])
    assert result.exit_code == 1 and "expected a CSV with header" in result.output


@pytest.mark.parametrize("row", ["10,20,30", "10"])
def test_render_refuses_a_row_with_more_or_fewer_fields_than_its_header(tmp_path, row):
    """``lon,lat`` over ``10,20,30`` was read as the point (10, 20), the third field dropped (a held-out review)."""
    points = tmp_path / "p.csv"
    points.write_text(f"lon,lat\n{row}\n40,50\n")
    result = CliRunner().invoke(main, ["render", str(points), "-o", str(tmp_path / "a.png")])
    assert result.exit_code == 1 and "malformed CSV row 2 (" in result.output
    assert "fields, the header names 2)" in result.output and not (tmp_path / "a.png").exists()


def test_render_names_a_field_that_is_not_a_number(tmp_path):
    """A row of the right length with 'foo' in it was said to have the wrong number of fields."""
    points = tmp_path / "p.csv"
    points.write_text("x,y\n1,2\nfoo,3\n")
    result = CliRunner().invoke(main, ["render", str(points), "-o", str(tmp_path / "a.png")])
    assert result.exit_code == 1 and "malformed CSV row 3 (not a number): 'foo,3'" in result.output


@pytest.mark.parametrize("cell", ["1_0", "\u0663", "0x10", "1e", "- 1"])
def test_render_reads_only_decimal_numbers(tmp_path, cell):
    """Python's float() read "1_0" as 10 and Arabic-Indic digits as ours (a hostile sweep)."""
    points = tmp_path / "p.csv"
    points.write_text(f"x,y\n1,2\n{cell},3\n", encoding="utf-8")
    result = CliRunner().invoke(main, ["render", str(points), "-o", str(tmp_path / "a.png")])
    assert result.exit_code == 1 and "malformed CSV row 3 (not a number)" in result.output
    points.write_text("x,y\n1,2\n +1.5E+1 ,.5\n4.,-0\n")
    assert CliRunner().invoke(main, ["render", str(points), "-o", str(tmp_path / "a.png")]).exit_code == 0


def test_order_shortens_the_pen_path(torus_csv, tmp_path):
    image, _ = torus_csv
    arguments = ["torus", image, "-M", 300, "-N", 24, "--iterations", 10, "--init", "density", "--order"]
    result = run(arguments + ["-o", tmp_path / "o.csv"])
    assert result.exit_code == 0
    line = [text for text in result.output.splitlines() if "pen-up travel" in text][0]
    before, after = (float(value) for value in line.split("travel ")[1].split(" mm")[0].split(" -> "))
    assert after < 0.2 * before


def test_two_opt_improves_greedy_and_keeps_every_dot(rng):
    centres = rng.random((600, 2))
    greedy = greedy_order(centres)
    improved = two_opt(centres, greedy, closed=False)
    assert sorted(improved) == list(range(600))
    assert path_length(centres[improved]) < path_length(centres[greedy])
    order, before, after = plotter_order(centres)
    assert after == pytest.approx(path_length(centres[order])) and after < before / 5


def test_two_opt_untangles_a_crossing():
    square = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0], [0.0, 2.0]])
    order = two_opt(square, np.arange(5), closed=False)
    assert path_length(square[order]) < path_length(square)


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_makefile_example_on_two_images(tmp_path):
    images = tmp_path / "images"
    images.mkdir()
    for name, level in (("a.png", 60), ("b.jpg", 160)):
        picture = np.full((12, 18), 255, dtype=np.uint8)
        picture[:, :9] = level
        Image.fromarray(picture).save(images / name)
    command = [
        "make",
        "-f",
        str(ROOT / "examples" / "Makefile"),
        "-j2",
        f"IMAGES={images}",
        f"OUT={tmp_path / 'svg'}",
        f"STIPPLE={sys.executable} -m stipple",
        "POINTS=150",
        "OPTIONS=-N 16 --iterations 5 --order --quiet",
    ]
    result = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    for name in ("a.svg", "b.svg"):
        text = (tmp_path / "svg" / name).read_text()
        assert text.count("<circle") - text.count('class="copy"') == 150
    again = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path)
    assert "Nothing to be done" in again.stdout or again.stdout.strip() == "" or "is up to date" in again.stdout


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_makefile_example_deletes_an_interrupted_drawing(tmp_path):
    """A run stopped by a signal writes the dots it reached and exits non-zero (143 for SIGTERM): make must not
    keep that SVG as if it were finished, and must redo it next time."""
    images = tmp_path / "images"
    images.mkdir()
    Image.fromarray(np.full((12, 18), 90, dtype=np.uint8)).save(images / "a.png")
    interrupted = tmp_path / "interrupted.sh"
    interrupted.write_text(f'#!/bin/sh\n"{sys.executable}" -m stipple "$@"\nexit 143\n')
    interrupted.chmod(0o755)
    command = ["make", "-f", str(ROOT / "examples" / "Makefile"), f"IMAGES={images}", f"OUT={tmp_path / 'svg'}"]
    options = ["POINTS=150", "OPTIONS=-N 16 --iterations 5 --quiet"]
    failed = subprocess.run([*command, f"STIPPLE={interrupted}", *options], capture_output=True, text=True)
    assert failed.returncode != 0
    assert not (tmp_path / "svg" / "a.svg").exists()
    again = subprocess.run([*command, f"STIPPLE={sys.executable} -m stipple", *options], capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert (tmp_path / "svg" / "a.svg").read_text().count("<circle") >= 150
