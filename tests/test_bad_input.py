"""Every bad input: one line on stderr naming the problem, a documented exit code, outputs untouched."""

import json
import zipfile

import numpy as np
import PIL.Image
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.checkpoint import save_checkpoint
from stipple.cli import main
from stipple.halftone import run
from stipple.torus import torus_problem

KEEP = "precious\n"


@pytest.fixture
def files(tmp_path):
    image = tmp_path / "ok.png"
    Image.fromarray(np.tile(np.arange(0, 240, 15, dtype=np.uint8), (12, 1))).save(image)
    output = tmp_path / "out.csv"
    output.write_text(KEEP)
    return tmp_path, image, output


def invoke(args, expected_code=1):
    result = CliRunner().invoke(main, [str(a) for a in args])
    assert result.exit_code == expected_code, result.output
    assert "Traceback" not in result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 if expected_code == 1 else lines, result.output
    return result.output


def check_torus(args, message, files, expected_code=1):
    _, _, output = files
    text = invoke(["torus", *args, "-M", 30, "-N", 8, "--iterations", 2, "-q", "-o", output], expected_code)
    assert message in text
    assert output.read_text() == KEEP


def write(path, data):
    path.write_bytes(data)
    return path


def npy(path, array):
    np.save(path, array)
    return path


def test_missing_file(files):
    check_torus([files[0] / "nope.png"], "cannot read", files)


def test_directory_instead_of_file(files):
    check_torus([files[0]], "cannot read", files)


def test_empty_file(files):
    check_torus([write(files[0] / "empty.png", b"")], "file is empty", files)


def test_truncated_png(files):
    data = files[1].read_bytes()
    check_torus([write(files[0] / "cut.png", data[: len(data) // 2])], "cannot decode image", files)


def test_not_an_image(files):
    check_torus([write(files[0] / "notes.png", b"just some text\n")], "cannot decode image", files)


def test_truncated_npy(files):
    full = npy(files[0] / "full.npy", np.ones((20, 20))).read_bytes()
    check_torus([write(files[0] / "cut.npy", full[:100])], "corrupt or truncated .npy", files)


@pytest.mark.parametrize(
    "array,message",
    [
        (np.full((4, 4), np.nan), "NaN or infinite"),
        (np.array([[1.0, np.inf], [0.0, 1.0]]), "NaN or infinite"),
        (np.ones((3, 4, 5)), "expected a 2-D image or map"),
        (np.ones(7), "expected a 2-D image or map"),
        (np.ones((1, 1)), "at least 2×2"),
        (np.full((5, 5), 3.0), "map is constant (3); nothing to rescale (give --range LO HI"),
        (np.zeros((5, 5)), "map is constant"),
        (np.array([["a", "b"], ["c", "d"]]), "must hold real numbers"),
    ],
)
def test_bad_arrays(files, array, message):
    check_torus([npy(files[0] / "bad.npy", array)], message, files)


def test_object_npy_is_never_unpickled(files):
    path = files[0] / "objects.npy"
    np.save(path, np.array([{"evil": 1}, None], dtype=object), allow_pickle=True)
    check_torus([path], "holds Python objects", files)


def test_all_white_image(files):
    Image.new("L", (8, 8), 255).save(files[0] / "white.png")
    check_torus([files[0] / "white.png"], "blank (all white)", files)


def test_all_white_map_on_the_sphere(files):
    Image.new("L", (8, 4), 255).save(files[0] / "white.png")
    text = invoke(["sphere", files[0] / "white.png", "-q", "-o", files[2]])
    assert "zero everywhere" in text and files[2].read_text() == KEEP


def test_decompression_bomb(files, monkeypatch):
    monkeypatch.setattr(PIL.Image, "MAX_IMAGE_PIXELS", 50)
    check_torus([files[1]], "decompression-bomb guard", files)


@pytest.mark.parametrize(
    "option,message",
    [
        (["-M", "0"], "number of points must be an integer in [1,"),
        (["-M", "-5"], "number of points must be an integer in [1,"),
        (["-M", "999999999"], "number of points must be an integer in [1,"),
        (["-M", "20000000", "-N", "8192"], "GiB of memory, more than"),
        (["-N", "9"], "bandwidth must be an even integer"),
        (["-N", "-2"], "bandwidth must be an even integer"),
        (["-N", "100000"], "bandwidth must be an even integer"),
        (["--threads", "0"], "threads must be an integer"),
        (["--epsilon", "1e-20"], "epsilon must be a number"),
        (["--checkpoint-every", "soon"], "checkpoint-every must be like"),
        # Named as the library's checkpoint_iterations, the count echoed changed through a float (a hostile review)
        (["--checkpoint-every", "99999999999999999999999"], "checkpoint-every must be a whole number of iterations up"),
        (["--checkpoint-every", "9" * 400 + "s"], "checkpoint-every must be a finite time"),
        (["--dot-radius", "-1mm"], "dot-radius must be a length (mm"),
    ],
)
def test_bad_numbers(files, option, message):
    # Options come last so that they override the helper's -M / -N.
    _, image, output = files
    text = invoke(["torus", image, "-M", 30, "-N", 8, "--iterations", 2, "-q", "-o", output, *option])
    assert message in text and output.read_text() == KEEP


@pytest.mark.parametrize("value", ["-3", "0", "nan", "inf"])
def test_time_limit_named_as_the_option(files, value):
    # A usage error naming --time-limit (the library's own check named its parameter, time_limit).
    _, image, output = files
    text = invoke(["torus", image, "-M", 30, "-N", 8, "-q", "-o", output, "--time-limit", value], expected_code=2)
    assert "'--time-limit'" in text and output.read_text() == KEEP


@pytest.mark.parametrize(
    "args",
    [
        ["video", "--fps", "nan"],  # a range check lets nan through: it reached the MP4 writer as a traceback
        ["evaluate", "--sigma", "inf"],
        ["torus", "--settle", "nan"],
    ],
)
def test_ranges_refuse_nan_and_infinity(files, args):
    _, image, output = files
    command, *option = args
    extra = ["-M", 30, "-o", output] if command != "evaluate" else [image]
    text = invoke([command, image, *extra, *option], expected_code=2)
    assert f"'{option[0]}'" in text and "is not a finite number" in text and output.read_text() == KEEP


def test_usage_errors_exit_two(files):
    invoke(["torus", files[1], "-M", "many"], expected_code=2)
    invoke(["torus", files[1], "--backend", "fftw"], expected_code=2)
    invoke(["torus"], expected_code=2)


def test_unknown_output_extension(files):
    _, image, output = files
    text = invoke(["torus", image, "-M", 30, "-N", 8, "-q", "-o", output, "-o", files[0] / "dots.xyz"])
    assert "unknown output format .xyz" in text and output.read_text() == KEEP


@pytest.mark.parametrize("target", ["missing-dir/dots.csv", "folder.csv"])
def test_unwritable_output(files, target):
    _, image, output = files
    (files[0] / "folder.csv").mkdir()
    text = invoke(["torus", image, "-M", 30, "-N", 8, "-q", "-o", output, "-o", files[0] / target])
    assert ("does not exist" in text or "is a directory" in text) and output.read_text() == KEEP


def test_read_only_filesystem_is_caught_before_the_run(files):
    _, image, output = files
    text = invoke(["torus", image, "-M", 30, "-N", 8, "-q", "-o", output, "-o", "/proc/dots.csv"])
    assert "not writable" in text and output.read_text() == KEEP


def saved_checkpoint(tmp_path, image_weights):
    problem = torus_problem(image_weights, 30, 8, threads=1)
    path = tmp_path / "good.npz"
    run(problem, iterations=2, checkpoint=path)
    return path


def weights_of(image):
    from stipple import load_density

    return load_density(image)


def resume(files, checkpoint):
    _, image, output = files
    args = ["torus", image, "-M", 30, "-N", 8, "--iterations", 4, "-q", "-o", output]
    return invoke(args + ["--checkpoint", checkpoint, "--resume"])


def test_truncated_checkpoint(files):
    good = saved_checkpoint(files[0], weights_of(files[1])).read_bytes()
    text = resume(files, write(files[0] / "cut.npz", good[: len(good) // 2]))
    assert "corrupt or truncated checkpoint" in text and files[2].read_text() == KEEP


def test_corrupt_checkpoint(files):
    text = resume(files, write(files[0] / "noise.npz", bytes(range(256)) * 10))
    assert "not a stipple checkpoint (not a .npz archive)" in text


def test_foreign_checkpoint(files):
    path = files[0] / "foreign.npz"
    np.savez(path, weights=np.ones(3))
    assert "not a stipple checkpoint" in resume(files, path)


def test_newer_checkpoint(files):
    path = saved_checkpoint(files[0], weights_of(files[1]))
    with np.load(path) as archive:
        contents = dict(archive)
    metadata = json.loads(str(contents["metadata"]))
    metadata["version"] = 99
    contents["metadata"] = np.asarray(json.dumps(metadata))
    np.savez(path, **contents)
    assert "format version 99 is newer" in resume(files, path)


def test_checkpoint_with_damaged_arrays(files):
    path = saved_checkpoint(files[0], weights_of(files[1]))
    with np.load(path) as archive:
        contents = dict(archive)
    contents["points"] = contents["points"][:5]
    np.savez(path, **contents)
    assert "corrupt checkpoint" in resume(files, path)


def test_checkpoint_for_another_input(files):
    path = saved_checkpoint(files[0], 1 - weights_of(files[1]))
    assert "the input differs" in resume(files, path)


def test_resume_without_checkpoint_file(files):
    assert "no checkpoint to resume" in resume(files, files[0] / "never-written.npz")


def test_existing_checkpoint_is_not_clobbered(files):
    path = saved_checkpoint(files[0], weights_of(files[1]))
    before = path.read_bytes()
    text = invoke(["torus", files[1], "-M", 30, "-N", 8, "-q", "-o", files[2], "--checkpoint", path])
    assert "checkpoint exists" in text and path.read_bytes() == before


def test_checkpoint_is_a_zip_of_plain_arrays(files):
    path = saved_checkpoint(files[0], weights_of(files[1]))
    with zipfile.ZipFile(path) as archive:
        assert all(name.endswith(".npy") for name in archive.namelist())
    with np.load(path, allow_pickle=False) as archive:
        assert archive["points"].shape == (30, 2)
        assert json.loads(str(archive["metadata"]))["settings"]["points"] == 30


def test_save_is_atomic_when_the_target_directory_vanishes(files, monkeypatch):
    path = saved_checkpoint(files[0], weights_of(files[1]))
    before = path.read_bytes()
    problem = torus_problem(weights_of(files[1]), 30, 8, threads=1)
    state = run(problem, iterations=3).state

    def failing_replace(source, target):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("os.replace", failing_replace)
    with pytest.raises(Exception, match="No space left"):
        save_checkpoint(path, state, problem)
    assert path.read_bytes() == before
    assert not [p for p in files[0].iterdir() if p.name.startswith(".stipple-")]


@pytest.mark.parametrize(
    "change,message",
    [
        (["-M", 31], "points was 30, now 31"),
        (["-N", 10], "bandwidth was 8, now 10"),
        (["--hessian", "full"], "hessian was 'gauss-newton', now 'full'"),
    ],
)
def test_resume_refuses_a_different_problem(files, change, message):
    path = saved_checkpoint(files[0], weights_of(files[1]))
    args = ["torus", files[1], "-M", 30, "-N", 8, "--iterations", 4, "-q", "-o", files[2]]
    text = invoke(args + ["--checkpoint", path, "--resume", *change])
    assert message in text and files[2].read_text() == KEEP


def test_resume_refuses_another_kernel_or_domain(files):
    path = files[0] / "sphere.npz"
    base = ["sphere", "--uniform", "-M", 30, "-N", 4, "--iterations", 2, "-q", "-o", files[2]]
    assert CliRunner().invoke(main, [str(a) for a in base + ["--checkpoint", path]]).exit_code == 0
    assert "kernel was 'distance+design:7', now 'sobolev:1'" in invoke(
        base + ["--checkpoint", path, "--resume", "--kernel", "sobolev:1"]
    )
    text = invoke(["torus", files[1], "-M", 30, "-N", 4, "-q", "-o", files[2], "--checkpoint", path, "--resume"])
    # It said that the map, -M or a design's -t differed: the command differs (a hostile review).
    assert "checkpoint is of a stipple sphere or design run, not of this one" in text


def test_a_still_and_a_video_checkpoint_name_each_other(files):
    """A video's checkpoint given to ``stipple torus`` was "not a stipple checkpoint" (a fifth sweep)."""
    folder, image, output = files
    (folder / "frames").mkdir()
    for index in range(2):
        Image.open(image).save(folder / "frames" / f"{index}.png")
    video = ["video", folder / "frames", "-M", 30, "-N", 8, "--iterations", 2, "-q", "-o", folder / "v.csv"]
    still = ["torus", image, "-M", 30, "-N", 8, "--iterations", 2, "-q", "-o", output]
    assert CliRunner().invoke(main, [str(a) for a in [*video, "--checkpoint", folder / "v.npz"]]).exit_code == 0
    assert CliRunner().invoke(main, [str(a) for a in [*still, "--checkpoint", folder / "s.npz"]]).exit_code == 0
    text = invoke([*still, "--checkpoint", folder / "v.npz", "--resume"])
    assert "v.npz: checkpoint is of a stipple video run, not of this one" in text
    text = invoke([*video, "--checkpoint", folder / "s.npz", "--resume"])
    assert "s.npz: checkpoint is of a still's run (stipple torus, sphere, colour, line or design)" in text


@pytest.mark.parametrize("command", ["torus", "video"])
def test_a_checkpoint_that_is_not_a_regular_file_is_refused(files, tmp_path, command):
    """A zip reader read /dev/zero to its end (17.6 GB in 40 s, then killed) and waited on a FIFO for ever."""
    import os
    import subprocess
    import sys

    fifo = tmp_path / "run.npz"
    os.mkfifo(fifo)
    _, image, output = files
    source = image if command == "torus" else files[0]
    args = [command, source, "-M", 30, "-N", 8, "--iterations", 2, "-q", "-o", output, "--checkpoint", fifo]
    done = subprocess.run(
        [sys.executable, "-m", "stipple", *map(str, args), "--resume"], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 1 and "not a regular file" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and output.read_text() == KEEP


@pytest.mark.parametrize(
    "extra, code, message",
    [
        (["--checkpoint", ""], 1, "--checkpoint: an empty file name"),  # found after the whole run, when written
        (["-o", ""], 2, "an empty file name"),
        (["--config", "EMPTY"], 2, "no output: give one or more files"),  # output = [] ran, wrote nothing, exit 0
    ],
)
def test_empty_names_and_no_outputs_are_refused_before_the_run(files, extra, code, message):
    folder, image, output = files
    (folder / "empty.toml").write_text("output = []\n")
    extra = [str(folder / "empty.toml") if part == "EMPTY" else part for part in extra]
    text = invoke(["torus", image, "-M", 30, "-N", 8, "--iterations", 2, "-q", *extra], expected_code=code)
    assert message in text and output.read_text() == KEEP


def test_resuming_with_another_palette_names_the_palette(files):
    """A changed --palette on resume was reported as '-N (the bandwidth) differs' (a hostile review)."""
    path = files[0] / "colour.npz"
    base = ["torus", files[1], "-M", 60, "-N", 8, "--iterations", 2, "-q", "-o", files[2], "--checkpoint", path]
    assert CliRunner().invoke(main, [str(a) for a in base + ["--palette", "cmy"]]).exit_code == 0
    text = invoke(base + ["--resume", "--palette", "cmyk"])
    assert "--palette differs" in text


def test_a_deeply_nested_npy_header_gets_a_short_line(files):
    """numpy's message quoted the whole header: one line of 6 KB (a hostile review)."""
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': " + "(" * 3000 + "2,2" + ")" * 3000 + ", }"
    header += " " * (-(len(header) + 11) % 64) + "\n"
    data = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + bytes(32)
    text = invoke(["torus", write(files[0] / "deep.npy", data), "-M", 30, "-q", "-o", files[2]])
    assert "corrupt or truncated .npy" in text and len(text) < 400


@pytest.mark.parametrize(
    "first, then, named",
    [
        (["--palette", "cmy"], [], "--palette differs"),  # it said --order progressive
        (["--palette", "cmyk", "--black", "0.5"], ["--palette", "cmyk"], "--black differs"),  # it said -M
        (["--palette", "cmy", "--union-weight", "2"], ["--palette", "cmy"], "--union-weight differs"),
        (["--palette", "cmyk", "--black", "0.9"], ["--palette", "cmyk", "--black", "0.91"], "--black differs"),
        ([], ["--no-near-field"], "--near-field / --no-near-field differs"),  # it said -N (the bandwidth)
    ],
)
def test_a_colour_resume_names_the_colour_option_changed(files, first, then, named):
    """Compared over the current problem's settings only, a colour checkpoint resumed without --palette blamed
    --order progressive (its union's flat metric), and --black was named as '-M or --palette' (a code review)."""
    path = files[0] / "colour.npz"
    base = ["torus", files[1], "-M", 60, "-N", 8, "--iterations", 2, "-q", "-o", files[2], "--checkpoint", path]
    assert CliRunner().invoke(main, [str(a) for a in base + first]).exit_code == 0
    assert named in invoke(base + ["--resume", *then])


def test_a_call_in_an_npy_header_is_named_not_shown_as_an_address(files):
    """A header holding a call printed '<ast.Call object at 0x7f...>' (a hostile review)."""
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': f(3, 4), }"
    header += " " * (-(len(header) + 11) % 64) + "\n"
    data = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + bytes(96)
    text = invoke(["torus", write(files[0] / "call.npy", data), "-M", 30, "-q", "-o", files[2]])
    assert "corrupt or truncated .npy" in text and "a Python Call expression" in text and " at 0x" not in text
