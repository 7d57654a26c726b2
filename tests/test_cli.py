import sys
import warnings

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main


@pytest.fixture
def image_path(tmp_path):
    gradient = np.tile(np.linspace(0, 255, 24, dtype=np.uint8), (16, 1))
    path = tmp_path / "ramp.png"
    Image.fromarray(gradient).save(path)
    return path


def run(args, **kwargs):
    return CliRunner().invoke(main, [str(a) for a in args], **kwargs)


def test_writes_csv_svg_png(image_path, tmp_path):
    outputs = [tmp_path / name for name in ("dots.csv", "dots.svg", "dots.png")]
    args = ["torus", image_path, "-M", 150, "-N", 24, "--iterations", 5, "-q"]
    result = run(args + [item for path in outputs for item in ("-o", path)])
    assert result.exit_code == 0, result.output
    table = np.loadtxt(outputs[0], delimiter=",", skiprows=1)
    assert outputs[0].read_text().startswith("x,y\n")
    assert table.shape == (150, 2)
    assert np.all((table[:, 0] >= 0) & (table[:, 0] < 24) & (table[:, 1] >= 0) & (table[:, 1] < 16))
    # More dots where the ramp is dark (left): w = 1 - u.
    assert np.sum(table[:, 0] < 12) > 2 * np.sum(table[:, 0] >= 12)
    svg = outputs[1].read_text()
    assert (
        svg.count("<circle") - svg.count('class="copy"') == 150
        and 'width="200mm"' in svg
        and 'height="133.333mm"' in svg
    )
    picture = Image.open(outputs[2])
    assert picture.size == (1024, 683)
    assert np.asarray(picture).min() < 50


def test_csv_to_stdout_by_default(image_path):
    result = run(["torus", image_path, "-M", 40, "-N", 12, "--iterations", 2, "-q"])
    assert result.exit_code == 0
    lines = result.stdout.splitlines()
    assert lines[0] == "x,y" and len(lines) == 41


def test_invert_puts_dots_on_white(image_path):
    result = run(["torus", image_path, "-M", 200, "-N", 16, "--iterations", 3, "-q", "--invert"])
    table = np.loadtxt(result.stdout.splitlines()[1:], delimiter=",")
    assert np.sum(table[:, 0] >= 12) > 2 * np.sum(table[:, 0] < 12)


def test_same_seed_same_bytes(image_path):
    args = ["torus", image_path, "-M", 60, "-N", 12, "--iterations", 4, "-q", "--threads", 1]
    assert run(args).stdout == run(args).stdout
    assert run(args).stdout != run(args + ["--seed", 7]).stdout


def test_init_from_csv_continues_from_those_points(image_path, tmp_path):
    start = tmp_path / "start.csv"
    run(["torus", image_path, "-M", 60, "-N", 12, "--iterations", 0, "-q", "-o", start])
    result = run(["torus", image_path, "-M", 60, "-N", 12, "--iterations", 0, "-q", "--init", start])
    assert result.stdout == start.read_text()


def test_an_init_made_for_another_image_is_warned_about(image_path, tmp_path):
    """A start from a larger image's run wrapped around without a word (1764 of 5000 points outside; stipple
    render warns about the same file: a held-out review)."""
    start = tmp_path / "start.csv"
    start.write_text("x,y\n1.5,2.5\n30.5,4.5\n10.5,20.5\n")  # the ramp is 24 x 16 pixels
    args = ["torus", image_path, "-M", 3, "-N", 12, "--iterations", 0, "--init", start, "-o", tmp_path / "a.csv"]
    assert "2 of 3 points lie outside the 24×16 image" in run(args).stderr
    assert "outside" not in run([*args, "-q"]).stderr


@pytest.mark.parametrize(
    "extra,message",
    [
        (["-M", 0], "number of points must be an integer in [1,"),
        (["-N", 7], "bandwidth must be an even integer"),
        (["-N", -4], "bandwidth must be an even integer"),
        (["-o", "dots.xyz"], "unknown output format .xyz"),
        (["-o", "/nonexistent-dir/dots.csv"], "does not exist"),
        (["--width", "wide"], "width must be a length (mm"),
        (["--gamma", 0], "gamma must be a positive number"),
        (["--tol", -1], "tol must be a positive number"),
        (["--settle", 1], "settle must be a number in [0, 1)"),
    ],
)
def test_bad_options_give_one_line_errors(image_path, extra, message):
    result = run(["torus", image_path, "-M", 20, "-N", 8, "--iterations", 1, "-q"] + extra)
    assert result.exit_code == 1
    assert message in result.output
    assert "Traceback" not in result.output and len(result.output.strip().splitlines()) == 1


def test_usage_errors_exit_two(image_path):
    result = run(["torus", image_path, "--backend", "nope"])
    assert result.exit_code == 2
    result = run(["torus", image_path, "--beta", "fletcher-reeves"])
    assert result.exit_code == 2
    result = run(["torus", image_path, "--settle", -0.1])
    assert result.exit_code == 2
    result = run(["torus", image_path, "--iterations", -1])
    assert result.exit_code == 2


def test_run_options_reach_the_run(image_path):
    """--beta daniel with --settle 0 and --no-correct is 0.1's method: the same points as the library's run."""
    from stipple.halftone import run as library_run
    from stipple.io.images import load_density
    from stipple.torus import DERIVATIVE_EPSILON, torus_problem

    args = ["torus", image_path, "-M", 150, "-N", 24, "--iterations", 30, "--threads", 1, "-q"]
    paper = run(args + ["--beta", "daniel", "--settle", 0, "--no-correct"])
    default = run(args)
    assert paper.exit_code == 0 and default.exit_code == 0
    problem = torus_problem(load_density(image_path), 150, 24, threads=1, derivative_epsilon=DERIVATIVE_EPSILON)
    expected = library_run(problem, iterations=30, beta="daniel", settle=0, correct=False).points * [24, 16]
    np.testing.assert_allclose(np.loadtxt(paper.output.splitlines(), delimiter=",", skiprows=1), expected, atol=1e-5)
    assert paper.output != default.output


def test_missing_and_blank_inputs(tmp_path):
    result = run(["torus", tmp_path / "missing.png", "-q"])
    assert result.exit_code == 1 and "cannot read" in result.output
    blank = tmp_path / "white.png"
    Image.new("L", (8, 8), 255).save(blank)
    result = run(["torus", blank, "-q"])
    assert result.exit_code == 1 and "blank" in result.output
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # the peak note's ratio divided by the zero mean first
        result = run(["torus", blank])
    assert result.exit_code == 1 and result.output.strip().splitlines() == [
        "Error: the image is blank (all white) or the map zero everywhere: there is nothing to place dots on"
    ]


def test_image_from_stdin(image_path):
    args = ["torus", "-", "-M", 40, "-N", 12, "--iterations", 2, "-q"]
    from_stdin = run(args, input=image_path.read_bytes())
    from_file = run(["torus", image_path] + args[2:])
    assert from_stdin.exit_code == 0 and from_stdin.stdout == from_file.stdout


@pytest.mark.parametrize(("threads", "shown"), [(1, "threads=1 (transforms 1)"), (2, "threads=2 (transforms 1)")])
def test_verbose_names_the_threads_asked_for_and_the_transforms_share(image_path, tmp_path, threads, shown):
    """With the near field the transforms run on half of the threads beside the pairs: -v printed only that share
    (threads=1 for --threads 2), which read like the option being ignored."""
    args = ["torus", image_path, "-M", 150, "--iterations", 2, "--threads", threads, "-v", "-o", tmp_path / "d.csv"]
    result = run(args)
    assert result.exit_code == 0 and shown in result.output, result.output


def test_verbose_on_the_sphere_names_the_adjoints_one_thread(tmp_path):
    """The sphere's adjoint SHTs run on one thread (bit-reproducible sums): -v says so beside the syntheses'."""
    args = ["sphere", "builtin:gaussians", "-M", 200, "--iterations", 2, "--threads", 2, "-v", "-o", tmp_path / "d.csv"]
    result = run(args)
    assert result.exit_code == 0 and "threads=2 (transforms 2, adjoints 1)" in result.output, result.output


def test_the_progress_bar_counts_each_phase_without_the_cap_as_its_total(monkeypatch):
    """A run's phases each count from 0 and mostly stop when the energy settles: the bar showed the 2000-iteration
    cap as its total (113/2000, 1:30 to go, for a 5 s run) and its count fell back between phases."""
    import io
    from types import SimpleNamespace

    from stipple.cli.supervise import Progress

    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)
    progress = Progress(enabled=True)
    for phase in (37, 5):
        for iteration in range(phase):
            progress(SimpleNamespace(iteration=iteration, energy=1.0, relative_gradient_norm=0.5))
    progress.close()
    shown = [line for line in stream.getvalue().replace("\r", "\n").splitlines() if "it" in line]
    assert "2000" not in stream.getvalue() and shown[-1].lstrip().startswith("4it"), shown[-3:]


def test_the_video_bar_shows_from_the_start_and_names_the_frame_just_finished(monkeypatch):
    """The bar appeared only when the cold first frame (the longest) was done, then named the frame before."""
    import io
    from types import SimpleNamespace

    from stipple.cli.video import FrameProgress

    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)
    progress = FrameProgress(3, enabled=True)
    progress.start()
    assert "0/3" in stream.getvalue() and "the first frame: a cold run" in stream.getvalue()
    progress.bar.mininterval = 0  # as if the frame took a while: the update redraws the bar
    progress(SimpleNamespace(index=7, iterations=12, replayed=False))
    assert stream.getvalue().replace("\r", "\n").splitlines()[-1].endswith("frame 7: 12 iterations]")
    progress.close()


@pytest.mark.parametrize("command", ["torus", "colour", "line"])
def test_flat_commands_refuse_geojson_before_any_work(image_path, command):
    """The formats are checked with the other outputs, before the run (a held-out sweep waited 10 s for
    'GeoJSON output is for sphere points'), and the formats offered are the command's own."""
    result = run([command, image_path, "-M", 40, "-q", "-o", "dots.geojson"])
    assert result.exit_code == 1, result.output
    assert "dots.geojson: GeoJSON output is for sphere points; use one of .csv, .svg, .png" in result.output


@pytest.mark.parametrize("light, hinted", [(40, True), (0, False)])
def test_the_dark_image_note_offers_invert_only_where_it_has_light_parts(tmp_path, light, hinted):
    """An image black all over is blank under --invert: the note did offer it (a held-out sweep followed it)."""
    pixels = np.zeros((16, 24), np.uint8)
    pixels[:4, :4] = light
    Image.fromarray(pixels).save(tmp_path / "dark.png")
    result = run(["torus", tmp_path / "dark.png", "-M", 40, "-N", 8, "--iterations", 1, "-o", tmp_path / "d.csv"])
    assert result.exit_code == 0, result.output
    assert "dark on average" in result.output
    assert ("--invert" in result.output) == hinted
    if hinted:
        inverted = run(["torus", tmp_path / "dark.png", "-M", 40, "-N", 8, "--iterations", 1, "--invert", "-q"])
        assert inverted.exit_code == 0, inverted.output


def test_a_dark_photo_gets_the_dark_note_not_the_faint_one(tmp_path):
    """A dark photo (gray values spanning a third of the range) got both notes; following the faint one stretched
    it lighter all over and sent its few highlights to white (a held-out review)."""
    rng = np.random.default_rng(0)
    pixels = (255 * np.clip(rng.normal(0.1, 0.05, (32, 48)), 0, 0.35)).astype(np.uint8)
    Image.fromarray(pixels).save(tmp_path / "dark.png")
    result = run(["torus", tmp_path / "dark.png", "-M", 60, "-N", 8, "--iterations", 1, "-o", tmp_path / "d.csv"])
    assert result.exit_code == 0, result.output
    assert "dark on average" in result.output and "gray values span only" not in result.output


@pytest.mark.parametrize("spot, options, noted", [(True, [], True), (True, ["-q"], False), (False, [], False)])
def test_a_small_dark_spot_on_a_light_page_says_why_the_run_is_long(tmp_path, spot, options, noted):
    """The spot's dots, packed far closer, raise the bandwidth (to 4456 for 10000 dots on a 600 x 400 page: 62 s
    and 2.2 GB) without a word."""
    rows, columns = np.mgrid[0:60, 0:90]
    darkness = np.exp(-((rows - 30.0) ** 2 + (columns - 45.0) ** 2) / 2.0) if spot else columns / 90
    Image.fromarray((255 * (1 - darkness)).astype(np.uint8)).save(tmp_path / "page.png")
    arguments = ["torus", tmp_path / "page.png", "-M", 300, "--iterations", 1, "--no-correct", *options]
    result = run([*arguments, "-o", tmp_path / "d.csv"])
    assert result.exit_code == 0, result.output
    assert ("the bandwidth rises from" in result.output) == noted, result.output


def test_checkpoint_every_without_a_checkpoint_is_refused(image_path, tmp_path):
    args = ["torus", image_path, "-M", 20, "-N", 8, "--iterations", 2, "-q", "-o", tmp_path / "d.csv"]
    result = run([*args, "--checkpoint-every", 5])
    assert result.exit_code == 1 and "--checkpoint-every is for --checkpoint" in result.output
    assert run([*args, "--checkpoint-every", 5, "--checkpoint", tmp_path / "c.npz"]).exit_code == 0


@pytest.mark.parametrize("command", [["torus", "IMAGE"], ["sphere", "builtin:gaussians"]])
@pytest.mark.parametrize("count", ["0", "-5"])
@pytest.mark.parametrize("outputs", [["-o", "-"], ["-o", "x.png"], ["--dot-style", "filled", "-o", "x.svg"]])
def test_a_count_below_one_is_one_line_before_the_peak_note(image_path, command, count, outputs):
    """-M is checked where it enters: the peak note, the PNG's size and the pen's notes used it first (a traceback
    for -M -5 with a PNG, numpy warnings and notes before the error for -M 0: two code reviews)."""
    command = [image_path if part == "IMAGE" else part for part in command]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        result = run([*command, "-M", count, *outputs])
    assert result.exit_code == 1 and result.output.strip().splitlines() == [
        f"Error: number of points must be an integer in [1, 20000000], not {count}"
    ], result.output


def test_the_peak_note_counts_a_pens_clipping_of_the_density(tmp_path):
    """A pen's dots are placed by the density clipped where they would pack too close: the note quoted the
    unclipped peak's bandwidth, not the run's (a code review)."""
    import re

    rows, columns = np.mgrid[0:60, 0:90]
    darkness = np.exp(-((rows - 30.0) ** 2 + (columns - 45.0) ** 2) / 2.0)
    Image.fromarray((255 * (1 - darkness)).astype(np.uint8)).save(tmp_path / "spot.png")
    arguments = ["torus", tmp_path / "spot.png", "-M", 300, "--iterations", 1, "--no-correct", "-o", tmp_path / "d.svg"]
    quoted = []
    for pen in ([], ["--dot-style", "point", "--pen-width", "0.5mm"]):
        result = run([*arguments, *pen])
        assert result.exit_code == 0, result.output
        quoted.append(int(re.search(r"rises from \d+ to (\d+)", result.output).group(1)))
    assert quoted[1] < 0.7 * quoted[0], quoted  # 328 and 178; both 328 before


@pytest.mark.parametrize(
    "args, option, text",
    [
        (["-M", "3_00"], "-M", "'3_00' is not a whole number in decimal digits or 'auto'"),
        (["-M", "\u0663\u0660\u0660"], "-M", "is not a whole number in decimal digits or 'auto'"),
        (["--seed", "\uff10"], "--seed", "is not a whole number in decimal digits"),
        (["--iterations", "1e3"], "--iterations", "'1e3' is not a whole number in decimal digits"),
        (["--gamma", "1_0"], "--gamma", "'1_0' is not a decimal number"),
        (["--range", "0", "1_0"], "--range", "'1_0' is not a decimal number"),
        (["--settle", "\u0661e-3"], "--settle", "is not a decimal number"),
    ],
)
def test_options_take_only_decimal_numbers(image_path, tmp_path, args, option, text):
    """click's int() and float() read "3_00" as 300 and other scripts' digits as ours (a hostile sweep)."""
    result = run(["torus", image_path, "-o", tmp_path / "o.csv", *args])
    assert result.exit_code == 2 and option in result.output and text in result.output
    assert not (tmp_path / "o.csv").exists()


def test_decimal_options_keep_signs_spaces_exponents_and_named_nan(image_path, tmp_path):
    args = ["torus", image_path, "-o", tmp_path / "o.csv", "-N", " 24 ", "--iterations", "+3", "--tol", "1E-3"]
    assert run(args + ["-M", " 150", "--gamma", ".5"]).exit_code == 0
    result = run(args + ["-M", "150", "--gamma", "NaN"])
    assert result.exit_code == 1 and "gamma must be a positive number, not nan" in result.output


def test_pairs_of_numbers_take_only_decimal_numbers(image_path, tmp_path):
    result = run(["torus", image_path, "-M", 100, "-o", tmp_path / "o.csv", "--levels", "0.1,0_9"])
    assert result.exit_code == 1 and "--levels must be 'auto' or BLACK,WHITE" in result.output
    result = run(["sphere", "--uniform", "-M", 100, "-o", tmp_path / "o.png", "--view", "1_0,0"])
    assert result.exit_code == 1 and "view must be LON,LAT in degrees, not '1_0,0'" in result.output


def test_evaluate_and_design_options_take_only_decimal_numbers(image_path, tmp_path):
    points = tmp_path / "p.csv"
    points.write_text("x,y\n1,2\n3,4\n")
    result = run(["evaluate", points, image_path, "-N", "2_4"])
    assert result.exit_code == 2 and "'2_4' is not a whole number in decimal digits" in result.output
    result = run(["design", "-t", "\u0664", "-o", tmp_path / "d.csv"])
    assert result.exit_code == 2 and "is not a whole number in decimal digits" in result.output


@pytest.mark.parametrize("command", [["torus"], ["sphere"], ["render"], ["evaluate"], ["video"]])
def test_an_empty_input_name_is_named(tmp_path, command):
    """``stipple torus "$UNSET"`` said "cannot read : No such file or directory" (a fifth sweep)."""
    result = run([*command, "", "-o", tmp_path / "o.csv"] if command != ["evaluate"] else [*command, ""])
    assert result.exit_code == 1 and "an empty file name (an unset shell variable?)" in result.output


@pytest.mark.parametrize("command", ["torus", "colour", "line", "video"])
def test_a_builtin_density_given_to_an_image_command_is_named(tmp_path, command):
    """``stipple torus builtin:gaussians`` said "No such file or directory" (a fifth sweep)."""
    result = run([command, "builtin:gaussians", "-M", 100, "-o", tmp_path / "o.csv"])
    assert result.exit_code == 1
    assert "builtin:gaussians: the built-in densities are the sphere's ('stipple sphere builtin:gaussians')" in (
        result.output
    )


@pytest.mark.parametrize(
    "option, value, message",
    [
        ("--color", "#ff000080", "color must be an opaque colour (no alpha"),
        ("--background", "", "background must be a colour such as"),
        ("--color", " ", "color must be a colour such as"),
    ],
)
def test_colours_with_alpha_or_empty_are_refused(image_path, tmp_path, option, value, message):
    """The alpha was dropped and an empty colour meant the default, without a word (a fifth sweep)."""
    result = run(["torus", image_path, "-M", 50, "-N", 12, "--iterations", 2, "-o", tmp_path / "o.svg", option, value])
    assert result.exit_code == 1 and message in result.output and not (tmp_path / "o.svg").exists()
    fine = run(["torus", image_path, "-M", 50, "-N", 12, "--iterations", 2, "-o", tmp_path / "o.svg", option, "#f00"])
    assert fine.exit_code == 0
    if option == "--color":
        assert 'fill="#ff0000"' in (tmp_path / "o.svg").read_text()
