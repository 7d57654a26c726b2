"""Issue 33: the newer commands under careless and hostile use; one test per row of the issue's table (row 1, the
image storages, is tests/test_image_formats.py). Every network test binds to 127.0.0.1 only."""

import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from safety_helpers import check_refused, snapshot

from stipple import batch as batch_module

FAST = ["-M", "30", "-N", "8", "--iterations", "2", "-q"]
ROOT_SAMPLE = Path(__file__).resolve().parents[1] / "samples" / "camera128.png"


def stipple(*args, timeout=60):
    """The command in a fresh process (its real stderr, its real exit), bounded by ``timeout`` seconds."""
    return subprocess.run(
        [sys.executable, "-m", "stipple", *map(str, args)], capture_output=True, text=True, timeout=timeout
    )


def one_line(result, code, message):
    assert result.returncode == code, result.stderr
    assert "Traceback" not in result.stderr + result.stdout, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert message in result.stderr, result.stderr


@pytest.fixture
def grad(tmp_path):
    """A 24×16 gray ramp, dark on the left."""
    path = tmp_path / "grad.png"
    Image.fromarray(np.tile(np.linspace(10, 240, 24).astype(np.uint8), (16, 1))).save(path)
    return path


class SilentListener:
    """A TCP listener on 127.0.0.1 that accepts every connection and never answers (bounded: it stops when
    closed, and after 60 s at most)."""

    def __init__(self):
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.socket.bind(("127.0.0.1", 0))
        self.socket.listen(8)
        self.socket.settimeout(0.2)
        self.port = self.socket.getsockname()[1]
        self.accepted, self.stopped = [], threading.Event()
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def serve(self):
        deadline = time.monotonic() + 60
        while not self.stopped.is_set() and time.monotonic() < deadline:
            try:
                self.accepted.append(self.socket.accept()[0])
            except OSError:
                continue

    def close(self):
        self.stopped.set()
        self.thread.join(5)
        for connection in self.accepted:
            connection.close()
        self.socket.close()


@pytest.fixture
def listener():
    server = SilentListener()
    yield server
    server.close()


def free_port():
    """A port on 127.0.0.1 with nothing listening (bound, then released)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


# Row 2: a listener that accepts and never answers: one line within ~10 s (CONNECT_TIMEOUT), not a hang.
def test_row2_a_silent_scheduler_gets_one_line_within_the_timeout(grad, tmp_path, listener):
    pytest.importorskip("distributed")
    started = time.monotonic()
    result = stipple("batch", grad, "-d", tmp_path / "out", *FAST, "--scheduler", f"tcp://127.0.0.1:{listener.port}")
    elapsed = time.monotonic() - started
    one_line(result, 1, "no answer within")
    assert listener.accepted, "the listener was never reached"
    assert elapsed < batch_module.CONNECT_TIMEOUT + 8, elapsed


# Rows 4 and 13: bad addresses and ports are our own checks (no Dask needed), quick, one line, no __del__ traceback.
@pytest.mark.parametrize(
    "address, message",
    [
        ("bogus:notaport", "invalid port"),
        ("", "no host"),
        ("http://127.0.0.1:{port}", "http:// is not supported"),
        ("tcp://127.0.0.1:99999", "invalid port '99999'"),
        ("tcp://127.0.0.1:0", "invalid port '0'"),
    ],
)
def test_rows4_13_a_bad_address_is_refused_at_once_before_any_work(grad, tmp_path, address, message):
    started = time.monotonic()
    result = stipple("batch", grad, "-d", tmp_path / "out", *FAST, "--scheduler", address.format(port=free_port()))
    one_line(result, 1, message)
    assert time.monotonic() - started < 8
    assert not (tmp_path / "out").exists()


def test_row13_nothing_listening_is_connection_refused_quickly(grad, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", type(sys)("distributed"))
    sys.modules["distributed"].Client = None  # never reached: the probe is refused first
    address = f"tcp://127.0.0.1:{free_port()}"
    started = time.monotonic()
    with pytest.raises(batch_module.StippleError, match="connection refused"):
        batch_module.connect(address)
    assert time.monotonic() - started < batch_module.PROBE_TIMEOUT + 1


def test_row13_refused_from_the_command_line_with_dask(grad, tmp_path):
    pytest.importorskip("distributed")
    started = time.monotonic()
    result = stipple("batch", grad, "-d", tmp_path / "out", *FAST, "--scheduler", f"tcp://127.0.0.1:{free_port()}")
    one_line(result, 1, "connection refused")
    assert time.monotonic() - started < 8


def test_scheduler_address_parts():
    assert batch_module.scheduler_address("tcp://127.0.0.1:8786") == ("tcp", "127.0.0.1", 8786)
    assert batch_module.scheduler_address("127.0.0.1") == ("tcp", "127.0.0.1", 8786)
    assert batch_module.scheduler_address("tls://[::1]:9000") == ("tls", "::1", 9000)


# Row 5: a read-only existing output is refused as torus refuses it, before any work.
def test_row5_a_read_only_output_of_a_batch_is_refused(grad, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    kept = out / "grad.csv"
    kept.write_text("precious\n")
    kept.chmod(0o444)
    os.utime(kept, (1, 1))  # older than the image: not done, so the batch would redo it
    before = snapshot(tmp_path)
    try:
        result = stipple("batch", grad, "-d", out, *FAST, "--format", "csv")
        check_refused(result, 1, "is read-only", tmp_path, before)
    finally:
        kept.chmod(0o644)


# Row 7: -M 0 or --levels 5,2: one usage error before any work and before the folder is made.
@pytest.mark.parametrize(
    "args, message",
    [
        (["-M", "0"], "number of points"),
        (["--levels", "5,2"], "levels must be"),
        (["--gamma", "-1"], "gamma"),
        (["-N", "3"], "even"),
        (["--tol", "0"], "tol"),
        (["--epsilon", "1"], "epsilon"),
    ],
)
def test_row7_a_bad_option_is_one_error_before_any_work(grad, tmp_path, args, message):
    second = tmp_path / "second.png"
    second.write_bytes(grad.read_bytes())
    result = stipple("batch", grad, second, "-d", tmp_path / "out", "--iterations", "2", "-q", *args)
    one_line(result, 1, message)
    assert not (tmp_path / "out").exists()


# Row 14: a read-only output folder is named, not an internal probe file.
def test_row14_a_read_only_folder_is_named(grad, tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        result = stipple("batch", grad, "-d", folder, *FAST)
        one_line(result, 1, f"{folder}: the output folder is read-only")
        assert "check" not in result.stderr
        assert os.listdir(folder) == []
    finally:
        folder.chmod(0o755)


# Row 19: a quoted glob is expanded as `stipple video` expands one (natural order), and one that matches nothing
# is one line.
def test_row19_a_quoted_glob_is_expanded(grad, tmp_path):
    images = tmp_path / "in"
    images.mkdir()
    for name in ("2.png", "10.png"):
        (images / name).write_bytes(grad.read_bytes())
    (images / "notes.txt").write_text("not an image")
    result = stipple("batch", images / "*.png", "-d", tmp_path / "out", *FAST, "--format", "csv")
    assert result.returncode == 0, result.stderr
    assert sorted(os.listdir(tmp_path / "out")) == ["10.csv", "2.csv"]
    assert batch_module.expand_images([str(images / "*.png")]) == [str(images / "2.png"), str(images / "10.png")]
    missing = stipple("batch", images / "*.jpg", "-d", tmp_path / "none", *FAST)
    one_line(missing, 1, "no file matches")
    assert not (tmp_path / "none").exists()


@pytest.fixture
def grad64(tmp_path):
    """The issue's 64×64 gray gradient."""
    path = tmp_path / "grad.png"
    Image.fromarray(np.tile(np.linspace(0, 255, 64).astype(np.uint8), (64, 1))).save(path)
    return path


# Rows 3 and 9: a length or a bandwidth that would grow the line's grid is refused where it enters, naming the option
# typed and its value; an odd -N too.
@pytest.mark.parametrize(
    "args, message",
    [
        (["--length", "1"], "--length must be in [32, "),
        (["--length", "3"], "not 3.0"),
        (["--length", "1e12"], "not 1000000000000.0"),
        (["--length", "nan"], "--length must be"),
        (["-N", "100000"], "-N/--bandwidth must be an even integer in [2, "),
        (["-N", "3"], "-N/--bandwidth must be an even integer"),
    ],
)
def test_rows3_9_line_sizes_are_bounded_where_they_enter(grad64, tmp_path, args, message):
    output = tmp_path / "line.csv"
    started = time.monotonic()
    result = stipple("line", grad64, "-M", "300", "--iterations", "2", "-q", "-o", output, *args)
    one_line(result, 1, message)
    assert time.monotonic() - started < 20 and not output.exists()


def test_line_sizes_keep_the_padded_grid_in_bounds():
    from stipple.halftone import MAX_BANDWIDTH
    from stipple.line.problem import bandwidth_limit, blank_margin, length_bounds, line_settings

    weights = np.tile(np.linspace(0.1, 1.0, 64), (64, 1))
    low, high = length_bounds(weights.shape)
    assert blank_margin(low, weights.shape) <= 4 * 64 + 1
    for length in (low, 1000.0, high):
        limit = bandwidth_limit(length, weights.shape)
        longest = 64 + 2 * blank_margin(length, weights.shape)
        assert limit % 2 == 0 and int(2 * np.ceil(limit * longest / 64 / 2)) <= MAX_BANDWIDTH
        assert line_settings(weights, 300, length)[1] <= limit  # the default bandwidth too
    assert line_settings(weights, 4, None)[0] >= low  # a default length is held in bounds, not refused


# Row 8: a blur wider than the picture is a range error, not "out of memory".
def test_row8_evaluate_sigma_is_bounded(grad64, tmp_path):
    picture = tmp_path / "drawn.png"
    picture.write_bytes(grad64.read_bytes())
    result = stipple("evaluate", picture, grad64, "--sigma", "1e9")
    one_line(result, 1, "sigma must be in (0, 64]")


@pytest.fixture
def dots(grad64, tmp_path):
    path = tmp_path / "dots.csv"
    assert stipple("torus", grad64, *FAST, "-o", path).returncode == 0
    return path


# Row 10: resuming with another image or -M says which.
def test_row10_resume_with_another_image_or_M_says_so(grad64, tmp_path):
    checkpoint, output = tmp_path / "ck", tmp_path / "l.csv"
    base = ["line", grad64, "--iterations", "2", "-q", "-o", output, "--checkpoint", checkpoint]
    assert stipple(*base, "-M", "300").returncode == 0
    # A line's points are its nodes, which --length changes too (tests/test_safety_sweep3.py).
    one_line(stipple(*base, "-M", "200", "--resume"), 1, "-M (the line's vertices) differs (vertices was 300, now 200")
    small = tmp_path / "small.png"
    Image.open(grad64).resize((32, 32)).save(small)
    base[1] = small
    one_line(stipple(*base, "-M", "300", "--resume"), 1, "the image or --length differs (length was")


# Rows 11 and 12: --invert and --levels auto named.
def test_rows11_12_invert_and_levels_auto_are_named(tmp_path):
    black, gray = tmp_path / "black.png", tmp_path / "gray.png"
    Image.fromarray(np.zeros((16, 16), np.uint8)).save(black)
    Image.fromarray(np.full((16, 16), 128, np.uint8)).save(gray)
    one_line(stipple("torus", black, "--invert", *FAST, "-o", tmp_path / "a.csv"), 1, "blank under --invert")
    one_line(stipple("torus", gray, "--levels", "auto", *FAST, "-o", tmp_path / "b.csv"), 1, "auto: the image has one")


# Rows 15 and 16: an unknown builtin lists the names; options that do not apply to the input are refused.
@pytest.mark.parametrize(
    "args, message",
    [
        (["builtin:nosuch"], "unknown builtin 'nosuch': choose from builtin:gaussians"),
        (["{image}", "--floyd-steinberg", "100"], "--floyd-steinberg: for a drawn PICTURE"),
        (["{image}", "--sigma", "2"], "--sigma: for a drawn PICTURE"),
        (["{image}", "--inset", "2"], "--inset: for a drawn PICTURE"),
    ],
)
def test_rows15_16_evaluate_refuses_what_does_not_apply(dots, grad64, args, message):
    one_line(stipple("evaluate", dots, *[arg.format(image=grad64) for arg in args]), 1, message)


def test_row16_line_with_a_picture_is_refused(grad64, tmp_path):
    picture = tmp_path / "drawn.png"
    picture.write_bytes(grad64.read_bytes())
    one_line(stipple("evaluate", picture, grad64, "--line"), 1, "--line are for points, not pictures")


# Row 17: points made for a larger image warn; points made for this one do not.
def test_row17_points_outside_the_image_warn(dots, grad64, tmp_path):
    small = tmp_path / "small.png"
    Image.open(grad64).resize((32, 32)).save(small)
    result = stipple("evaluate", dots, small)
    assert result.returncode == 0 and "warning:" in result.stderr and "outside the 32×32 image" in result.stderr
    assert "warning" not in stipple("evaluate", dots, grad64).stderr


# Row 6: a blank frame is one line naming the frame; row 18: '%%' in a frame pattern is a literal '%'.
def test_row6_a_blank_frame_is_named(tmp_path):
    frames = tmp_path / "frames"
    frames.mkdir()
    ramp = np.tile(np.linspace(0, 255, 16).astype(np.uint8), (16, 1))
    for index, picture in enumerate([ramp, np.full_like(ramp, 255), ramp]):
        Image.fromarray(picture).save(frames / f"{index}.png")
    output = tmp_path / "v.csv"
    one_line(stipple("video", frames, *FAST, "-o", output), 1, "frame 1 is blank (all white)")
    assert not output.exists()


def test_row18_percent_percent_in_a_frame_pattern(tmp_path):
    from stipple.io.video import check_frame_pattern, frame_path

    frames, out = tmp_path / "frames", tmp_path / "out"
    frames.mkdir()
    out.mkdir()
    ramp = np.tile(np.linspace(0, 255, 16).astype(np.uint8), (16, 1))
    for index in range(2):
        Image.fromarray(ramp).save(frames / f"{index}.png")
    result = stipple("video", frames, *FAST, "-o", out / "100%%_%d.png")
    assert result.returncode == 0, result.stderr
    assert sorted(os.listdir(out)) == ["100%_0.png", "100%_1.png"]
    assert frame_path("a%%d_%03d.png", 7) == "a%d_007.png"
    with pytest.raises(batch_module.StippleError, match="needs one %d"):
        check_frame_pattern("100%%.png")


# Found by the sweep (bench/hostile_sweep.py): a blank image given to `line` (a traceback after the sizes were
# checked first), and a read-only folder for `torus` written into when run as root.
def test_sweep_line_on_a_blank_image_is_one_line(tmp_path):
    white = tmp_path / "white.png"
    Image.fromarray(np.full((16, 16), 255, np.uint8)).save(white)
    one_line(stipple("line", white, "-M", "120", "--iterations", "2", "-q", "-o", tmp_path / "o.csv"), 1, "blank")


def test_sweep_a_read_only_folder_is_refused_by_its_mode(grad, tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        one_line(stipple("torus", grad, *FAST, "-o", folder / "o.csv"), 1, "is read-only")
        assert os.listdir(folder) == []
    finally:
        folder.chmod(0o755)


def test_one_dot_and_a_subnormal_map_print_no_python_warnings(grad, tmp_path):
    """A single dot has no neighbour: the spread step's percentile of an infinite ratio printed a RuntimeWarning.
    A map whose values span a subnormal number halved its span to 0 and said it had NaN values."""
    single = stipple("torus", grad, "-M", "1", "-q", "-o", tmp_path / "one.csv")
    assert single.returncode == 0 and single.stderr == "", single.stderr
    assert len((tmp_path / "one.csv").read_text().splitlines()) == 2
    tiny = tmp_path / "tiny.npy"
    np.save(tiny, np.array([[0.0, 5e-324], [5e-324, 0.0]]))
    one_line(stipple("sphere", tiny, "-M", "10", "-o", tmp_path / "x.csv"), 1, "tiny.npy: the values span")
    # The sphere's one dot: its missing neighbour's index was used (an IndexError traceback); a --range of a
    # subnormal span overflowed the map's other values (a RuntimeWarning line; a hostile review).
    sphere = stipple("sphere", "builtin:gaussians", "-M", "1", "-q", "-o", tmp_path / "s.csv")
    assert sphere.returncode == 0 and sphere.stderr == "", sphere.stderr
    ordinary = tmp_path / "ordinary.npy"
    np.save(ordinary, np.random.default_rng(0).random((18, 36)))
    narrow = stipple("sphere", ordinary, "-M", "10", "--range", "0", "1e-310", "-q", "-o", tmp_path / "n.csv")
    assert narrow.returncode == 0 and narrow.stderr == "", narrow.stderr


def test_a_colour_image_on_stdin(tmp_path):
    """README: IMAGE may be '-'. Every colour path said "cannot read -"; the colour run reads its input twice (the
    inks, then the picture's target colour), which a pipe allows once."""
    rows, columns = np.mgrid[0:24, 0:36]
    rgb = np.stack([rows * 10, columns * 7, 255 - rows * 5], axis=-1).astype(np.uint8)
    image = tmp_path / "colour.png"
    Image.fromarray(rgb).save(image)
    data = image.read_bytes()

    def piped(*args):
        return subprocess.run([sys.executable, "-m", "stipple", *map(str, args)], input=data, capture_output=True)

    fast = ["-M", "200", "-N", "12", "--iterations", "3", "-q"]
    from_file = subprocess.run(
        [sys.executable, "-m", "stipple", "colour", image, *fast, "-o", "-"], capture_output=True
    )
    from_pipe = piped("colour", "-", *fast, "-o", tmp_path / "dots.csv", "-o", tmp_path / "dots.png")
    assert from_pipe.returncode == 0, from_pipe.stderr
    assert (tmp_path / "dots.csv").read_bytes() == from_file.stdout
    redrawn = piped("render", tmp_path / "dots.csv", "--like", "-", "-o", tmp_path / "again.png")
    assert redrawn.returncode == 0, redrawn.stderr
    measured = piped("evaluate", tmp_path / "dots.csv", "-")
    assert measured.returncode == 0 and b"dots (quota" in measured.stdout, measured.stderr


def test_options_that_empty_the_image_or_draw_for_minutes_are_named(tmp_path):
    """--levels or --gamma that leave no ink said "the image is blank (all white)" of an image with ink; a dot
    radius of 1 km drew for minutes; stipple line's --iterations said it capped the total (it caps the first
    phase)."""
    page = np.full((30, 30), 250, dtype=np.uint8)
    page[12:16, 4:26] = 235
    Image.fromarray(page).save(tmp_path / "page.png")
    one_line(stipple("torus", tmp_path / "page.png", *FAST, "--levels", "0.2,0.8"), 1, "no ink is left under --levels")
    one_line(stipple("torus", tmp_path / "page.png", *FAST, "--gamma", "1000"), 1, "no ink is left under --gamma")
    radius = stipple("torus", tmp_path / "page.png", *FAST, "--dot-radius", "1e6mm", "-o", tmp_path / "x.png")
    one_line(radius, 1, "more than half the drawing's --width")
    assert "first phase" in stipple("line", "--help").stdout


@pytest.mark.parametrize(
    "args, message",
    [
        (["torus", "{gray}", "--black", "0.3"], "--black: for runs with --palette"),
        (["torus", "{gray}", "--union-weight", "5"], "--union-weight: for runs with --palette"),
        (["torus", "{colour}", "--palette", "cmy", "--black", "0.3"], "--black is for --palette cmyk"),
        (["colour", "{colour}", "--palette", "gray", "--black", "0.3"], "--black is for --palette cmyk"),
        (["evaluate", "{dots}", "{gray}", "--black", "0.3"], "are for layered CSVs"),
        (["evaluate", "{picture}", "{gray}", "--palette", "cmy"], "not for a drawn PICTURE"),
    ],
)
def test_options_that_would_be_ignored_are_refused(grad, tmp_path, args, message):
    """They exited 0 with the same output as without them, while render refused the same misuse."""
    colour = tmp_path / "colour.png"
    Image.fromarray(np.dstack([np.full((16, 24), level, np.uint8) for level in (200, 90, 40)])).save(colour)
    dots, picture = tmp_path / "dots.csv", tmp_path / "dots.png"
    assert stipple("torus", grad, *FAST, "-o", dots, "-o", picture).returncode == 0
    names = {"gray": grad, "colour": colour, "dots": dots, "picture": picture}
    filled = [str(arg).format(**names) for arg in args]
    extra = [] if args[0] == "evaluate" else [*FAST, "-o", tmp_path / "out.csv"]
    one_line(stipple(*filled, *extra), 1, message)
    assert not (tmp_path / "out.csv").exists()


def test_render_and_evaluate_take_the_runs_gamma_and_levels(tmp_path):
    """render --like had no --gamma/--levels/--range: a --gamma 2 run was redrawn with RMSE 0.214 against its own
    PNG's 0.0069; evaluate refused --levels for points and measured a --levels auto run worse than random."""
    rows, columns = np.mgrid[0:40, 0:60]
    faint = (190 + 50 * np.sin(columns / 9.0) * np.cos(rows / 7.0)).astype(np.uint8)
    Image.fromarray(faint).save(tmp_path / "faint.png")
    for option in (["--gamma", "2"], ["--levels", "auto"]):
        dots, picture = tmp_path / "dots.csv", tmp_path / "dots.png"
        ran = stipple("torus", tmp_path / "faint.png", "-M", "600", "-q", *option, "-o", dots, "-o", picture)
        assert ran.returncode == 0, ran.stderr
        redrawn = stipple("render", dots, "--like", tmp_path / "faint.png", *option, "-o", tmp_path / "again.png")
        assert redrawn.returncode == 0, redrawn.stderr
        again, own = (np.asarray(Image.open(path).convert("L"), float) for path in (tmp_path / "again.png", picture))
        assert np.abs(again - own).mean() < 0.5  # the CSV's rounded positions (without --gamma 2: 46 gray levels)
        measured = stipple("evaluate", dots, tmp_path / "faint.png", *option, "--json", "-")
        assert measured.returncode == 0, measured.stderr
        assert json.loads(measured.stdout)["energy_ratio_to_iid"] < 0.1
    one_line(stipple("render", dots, "--gamma", "2", "-o", tmp_path / "x.png"), 1, "--gamma: for the tone of --like")


def test_an_output_under_a_file_and_points_before_the_origin_are_named(tmp_path):
    """-o FILE/x.csv said "directory ... does not exist" of a file; render without --like/--size drew a point at a
    negative x off the page, silently."""
    (tmp_path / "afile").write_text("")
    one_line(stipple("torus", ROOT_SAMPLE, *FAST, "-o", tmp_path / "afile" / "x.csv"), 1, "is a file, not a directory")
    points = tmp_path / "neg.csv"
    points.write_text("x,y\n1,2\n-5,3\n")
    one_line(stipple("render", points, "-o", tmp_path / "neg.svg"), 1, "1 points lie left of or above the origin")
    assert not (tmp_path / "neg.svg").exists()
    assert stipple("render", points, "--size", "10,10", "-o", tmp_path / "neg.svg").returncode == 0


def test_sphere_points_measured_against_another_lon0_are_warned_about(tmp_path):
    """Points of a peaked map measured with the wrong --lon0 lie where the map has no ink: the nearest-neighbour
    line came out empty, without a word."""
    lat = np.radians(90 - (np.arange(45) + 0.5) * 4)[:, None]
    lon = np.radians((np.arange(90) + 0.5) * 4)[None, :]
    cosine = np.sin(lat) * 0.5 + np.cos(lat) * 0.866 * np.cos(lon - np.radians(60))
    np.save(tmp_path / "peak.npy", np.exp(-((np.degrees(np.arccos(np.clip(cosine, -1, 1))) / 15) ** 2)))
    points = tmp_path / "peak.csv"
    assert (
        stipple("sphere", tmp_path / "peak.npy", "-M", "400", "--iterations", "5", "-q", "-o", points).returncode == 0
    )
    wrong = stipple("evaluate", points, tmp_path / "peak.npy", "--lon0", "-180")
    assert wrong.returncode == 0 and "warning: only 0 of 400 points lie where" in wrong.stderr
    assert "no point lies where the input has ink" in wrong.stdout
    right = stipple("evaluate", points, tmp_path / "peak.npy")
    assert right.returncode == 0 and "warning" not in right.stderr


@pytest.mark.parametrize(
    "args, message",
    [
        (["evaluate", "{layered}", "{colour}", "--levels", "0.3,0.7"], "--levels: not for layered CSVs"),
        (["evaluate", "{layered}", "{colour}", "--gamma", "2"], "--gamma: not for layered CSVs"),
        (["evaluate", "{layered}", "{colour}", "--invert"], "--invert: not for layered CSVs"),
        (["evaluate", "{sphere}", "builtin:gaussians", "--levels", "0.3,0.7"], "--levels is for images"),
        (["colour", "{colour}", "--palette", "gray", "--union-weight", "5", *FAST], "--union-weight is for several"),
        (["video", "{frames}", "--black", "0.3", *FAST], "--black: for runs with --palette"),
        (["render", "-", "--like", "-"], "'-' (stdin) may be given only once"),
    ],
)
def test_more_options_that_would_be_ignored_are_refused(grad, tmp_path, args, message):
    """The review of the first refusals: these still exited 0 with the output of a run without them."""
    colour = tmp_path / "colour.png"
    Image.fromarray(np.dstack([np.full((16, 24), level, np.uint8) for level in (200, 90, 40)])).save(colour)
    layered, sphere = tmp_path / "layered.csv", tmp_path / "sphere.csv"
    assert stipple("colour", colour, *FAST, "-o", layered).returncode == 0
    assert stipple("sphere", "builtin:gaussians", *FAST, "-o", sphere).returncode == 0
    frames = tmp_path / "frames"
    frames.mkdir()
    for index in range(2):
        (frames / f"{index}.png").write_bytes(grad.read_bytes())
    names = {"frames": frames, "colour": colour, "layered": layered, "sphere": sphere}
    filled = [str(arg).format(**names) for arg in args]
    one_line(stipple(*filled, "-o", tmp_path / "out.png") if args[0] == "render" else stipple(*filled), 1, message)
