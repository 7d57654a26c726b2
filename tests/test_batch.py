"""``stipple batch``: the same bytes as ``stipple torus`` image by image, here and on a real Dask cluster; one line
per failed image with the others written; the exit status counting failures; reruns that skip exactly the images
whose outputs all exist; and every check made before any work."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple import batch as batch_module
from stipple.batch import FAILED_BASE, FAILED_CAP, BatchOutcome, exit_status
from stipple.cli import main

SMALL = ["-M", "120", "--iterations", "40", "--threads", "1"]


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def failure_lines(result):
    return [line for line in result.stderr.splitlines() if line.startswith("stipple batch: ") and " of " not in line]


@pytest.fixture
def images(tmp_path):
    """Three small gray images that differ: a ramp, a disc and a checkerboard."""
    folder = tmp_path / "in"
    folder.mkdir()
    rows, columns = np.mgrid[0:24, 0:32]
    pictures = {
        "ramp": columns * 8,
        "disc": np.where((rows - 12) ** 2 + (columns - 16) ** 2 < 64, 30, 230),
        "check": np.where((rows // 6 + columns // 8) % 2, 40, 220),
    }
    paths = []
    for name, values in pictures.items():
        path = folder / f"{name}.png"
        Image.fromarray(values.astype(np.uint8)).save(path)
        paths.append(path)
    return paths


def torus_files(image, folder, options, formats=("csv", "png", "svg")):
    """What ``stipple torus`` writes for ``image``, run alone: {extension: bytes}."""
    outputs = [folder / f"torus-{image.stem}.{fmt}" for fmt in formats]
    result = run(["torus", image, *options, "-q", *[arg for path in outputs for arg in ("-o", path)]])
    assert result.exit_code == 0, result.output
    return {fmt: path.read_bytes() for fmt, path in zip(formats, outputs, strict=True)}


@pytest.mark.parametrize(
    "options",
    [SMALL, [*SMALL, "--invert", "--gamma", "1.5", "--seed", "7", "--order", "--dot-style", "circle"]],
    ids=["default", "invert-order-pen"],
)
def test_batch_writes_the_bytes_of_torus(images, tmp_path, options):
    out = tmp_path / "out"
    result = run(["batch", *images, "-d", out, "--format", "csv,png,svg", *options, "-q"])
    assert result.exit_code == 0, result.output
    assert sorted(os.listdir(out)) == sorted(f"{p.stem}.{fmt}" for p in images for fmt in ("csv", "png", "svg"))
    for image in images:
        expected = torus_files(image, tmp_path, options)
        for fmt, data in expected.items():
            assert (out / f"{image.stem}.{fmt}").read_bytes() == data, f"{image.stem}.{fmt}"


def test_outputs_differ_between_images_and_seeds(images, tmp_path):
    """The oracle above could pass if every file were the same: the images and seeds give different dots."""
    run(["batch", *images, "-d", tmp_path / "a", "--format", "csv", *SMALL, "-q"])
    run(["batch", *images, "-d", tmp_path / "b", "--format", "csv", *SMALL, "--seed", "1", "-q"])
    first = [(tmp_path / "a" / f"{p.stem}.csv").read_bytes() for p in images]
    assert len(set(first)) == len(images)
    assert all(first[i] != (tmp_path / "b" / f"{p.stem}.csv").read_bytes() for i, p in enumerate(images))


def test_failed_images_get_one_line_each_and_the_others_are_written(images, tmp_path):
    bad = images[0].parent / "bad.png"
    bad.write_text("not an image")
    missing = images[0].parent / "missing.png"
    out = tmp_path / "out"
    result = run(["batch", bad, *images, missing, "-d", out, *SMALL, "-q"])
    assert result.exit_code == FAILED_BASE + 2, result.output
    lines = failure_lines(result)
    assert len(lines) == 2 and lines[0].startswith(f"stipple batch: {bad}: ") and str(missing) in lines[1]
    assert "Traceback" not in result.output
    assert "2 failed of 5 images" in result.stderr
    assert sorted(os.listdir(out)) == sorted(f"{p.stem}.{fmt}" for p in images for fmt in ("csv", "png"))


def test_exit_status_counts_failures_and_is_capped():
    def outcomes(failed, done=3):
        return [BatchOutcome("x", "failed")] * failed + [BatchOutcome("y", "done")] * done

    assert exit_status(outcomes(0)) == 0
    assert exit_status([]) == 0
    assert exit_status(outcomes(1)) == 101
    assert exit_status(outcomes(7, done=0)) == 107
    assert exit_status(outcomes(FAILED_CAP + 10)) == FAILED_BASE + FAILED_CAP == 125


def test_an_output_that_is_a_folder_is_refused_before_any_work(images, tmp_path):
    out = tmp_path / "out"
    (out / "disc.png").mkdir(parents=True)
    result = run(["batch", *images, "-d", out, *SMALL, "-q"])
    assert result.exit_code == 1 and "disc.png: is a directory" in result.stderr, result.output
    assert result.stderr.count("\n") == 1
    assert sorted(os.listdir(out)) == ["disc.png"]


def test_an_output_folder_that_is_a_loop_of_links_is_named(images, tmp_path):
    """It said "cannot make the output folder (File exists)" (a fifth sweep)."""
    os.symlink(tmp_path / "b", tmp_path / "a")
    os.symlink(tmp_path / "a", tmp_path / "b")
    result = run(["batch", *images, "-d", tmp_path / "a", *SMALL, "-q"])
    assert result.exit_code == 1 and "a: a symbolic link to no folder (dangling, or a loop of links)" in result.stderr
    assert (tmp_path / "a").is_symlink() and (tmp_path / "b").is_symlink()


def test_an_output_that_cannot_be_written_fails_that_image_only(images, tmp_path, monkeypatch):
    out = tmp_path / "out"
    commit = batch_module.commit_outputs

    def commit_but_disc(items):  # disc's PNG cannot be renamed into place once the run has started
        if any(path.endswith("disc.png") for path, _ in items):
            (out / "disc.png").mkdir()
        commit(items)

    monkeypatch.setattr(batch_module, "commit_outputs", commit_but_disc)
    result = run(["batch", *images, "-d", out, *SMALL, "-q"])
    assert result.exit_code == FAILED_BASE + 1, result.output
    (line,) = failure_lines(result)
    assert line.startswith(f"stipple batch: {images[1]}: ")
    assert (out / "ramp.png").is_file() and (out / "check.png").is_file()
    assert not [name for name in os.listdir(out) if name.endswith(".tmp")]
    (out / "disc.png").rmdir()
    monkeypatch.undo()
    before = {name: os.stat(out / name).st_mtime_ns for name in ("ramp.png", "check.png")}
    assert run(["batch", *images, "-d", out, *SMALL, "-q"]).exit_code == 0  # disc not taken as done: redone
    assert (out / "disc.png").is_file()
    assert {name: os.stat(out / name).st_mtime_ns for name in before} == before


@pytest.mark.parametrize("second", ["sub/ramp.jpg", "sub/RAMP.png"])
def test_duplicate_stems_are_refused_before_any_work(images, tmp_path, second):
    other = images[0].parent / second
    other.parent.mkdir(exist_ok=True)
    if not other.exists():
        Image.open(images[1]).save(other)
    out = tmp_path / "out"
    result = run(["batch", *images, other, "-d", out, *SMALL])
    assert result.exit_code == 1
    assert result.stderr.count("\n") == 1 and "would both write" in result.stderr and "ramp" in result.stderr
    assert not out.exists()


def test_the_same_image_given_twice_is_stippled_once(images, tmp_path):
    """Overlapping globs name a file twice: it was refused as two images writing the same outputs ('rename
    one'), a held-out review."""
    again = images[0].parent / ".." / images[0].parent.name / images[0].name
    out = tmp_path / "out"
    result = run(["batch", images[0], again, "-d", out, *SMALL, "-q"])
    assert result.exit_code == 0, result.stderr
    assert sorted(os.listdir(out)) == ["ramp.csv", "ramp.png"]


def test_an_output_naming_an_input_is_refused(images):
    before = images[0].read_bytes()
    result = run(["batch", images[0], "-d", images[0].parent, "--format", "png", *SMALL])
    assert result.exit_code == 1 and "would overwrite the image" in result.stderr
    assert result.stderr.count("\n") == 1
    assert images[0].read_bytes() == before


@pytest.mark.parametrize(
    "args, message",
    [
        (["--format", "csv,jpg"], "format must be"),
        (["--init", "dots.csv"], "--init for a batch"),
        (["--seed", "-1"], "seed"),
        (["--scheduler", "tcp://127.0.0.1:1"], "cannot reach the Dask scheduler"),
        (["-d", ""], "-d: an empty folder name"),
    ],
)
def test_bad_settings_get_one_line_before_any_work(images, tmp_path, monkeypatch, args, message):
    monkeypatch.setattr(batch_module, "CONNECT_TIMEOUT", 1)
    if "--scheduler" in args:
        pytest.importorskip("distributed")
    result = run(["batch", *images, "-d", tmp_path / "out" / "a" / "b", *SMALL, *args])
    assert result.exit_code == 1, result.output
    assert message in result.stderr and result.stderr.count("\n") == 1, result.stderr
    assert not (tmp_path / "out").exists()  # an unreachable scheduler left the folders made (a hostile review)


def test_scheduler_without_distributed_names_the_extra(images, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    result = run(["batch", *images, "-d", tmp_path / "out", *SMALL, "--scheduler", "tcp://127.0.0.1:8786"])
    assert result.exit_code == 1
    assert "pip install 'stipple[cluster]'" in result.stderr and result.stderr.count("\n") == 1
    assert not (tmp_path / "out").exists()  # said before the folder is made (docs/errors.md)


def mtimes(folder):
    return {name: os.stat(folder / name).st_mtime_ns for name in sorted(os.listdir(folder))}


def age(folder, seconds):
    """Set every file's times ``seconds`` into the past (still newer than the inputs made before)."""
    for name in os.listdir(folder):
        stamp = time.time() - seconds
        os.utime(folder / name, (stamp, stamp))


def test_rerun_skips_done_images_and_redoes_the_rest(images, tmp_path):
    out = tmp_path / "out"
    for path in images:  # inputs older than anything written below
        os.utime(path, (time.time() - 3600, time.time() - 3600))
    assert run(["batch", *images, "-d", out, *SMALL, "-q"]).exit_code == 0
    first = {name: (out / name).read_bytes() for name in os.listdir(out)}
    age(out, 60)
    (out / "disc.png").unlink()  # as if cut off between disc's two renames
    before = mtimes(out)
    result = run(["batch", *images, "-d", out, *SMALL])
    assert result.exit_code == 0 and "1 done, 2 skipped" in result.stderr
    after = mtimes(out)
    changed = {name for name in after if after[name] != before.get(name)}
    assert changed == {"disc.csv", "disc.png"}
    assert {name: (out / name).read_bytes() for name in os.listdir(out)} == first  # the redo has the same bits

    os.utime(images[0], None)  # ramp.png edited after its outputs: redone
    age(out, 30)
    before = mtimes(out)
    result = run(["batch", *images, "-d", out, *SMALL])
    assert "1 done, 2 skipped" in result.stderr
    assert {name for name, stamp in mtimes(out).items() if stamp != before[name]} == {"ramp.csv", "ramp.png"}

    age(out, 10)
    before = mtimes(out)
    result = run(["batch", *images, "-d", out, *SMALL, "--force"])
    assert "3 done, 0 skipped" in result.stderr
    assert all(stamp != before[name] for name, stamp in mtimes(out).items())


def test_a_new_format_makes_images_not_done(images, tmp_path):
    out = tmp_path / "out"
    run(["batch", *images, "-d", out, "--format", "csv", *SMALL, "-q"])
    result = run(["batch", *images, "-d", out, "--format", "csv,svg", *SMALL])
    assert "3 done, 0 skipped" in result.stderr
    assert len(os.listdir(out)) == 6


def test_sigint_keeps_finished_images_and_a_rerun_completes(tmp_path):
    """A real process stopped by SIGINT mid-batch: exit 130, every file whole, no temporary; the rerun finishes."""
    folder = tmp_path / "in"
    folder.mkdir()
    rows, columns = np.mgrid[0:64, 0:64]
    images = []
    for index in range(4):
        path = folder / f"img{index}.png"
        Image.fromarray(((columns * (index + 2) + rows * 3) % 256).astype(np.uint8)).save(path)
        images.append(str(path))
    out = tmp_path / "out"
    args = [sys.executable, "-m", "stipple", "batch", *images, "-d", str(out), "-M", "3000", "--threads", "1", "-q"]
    process = subprocess.Popen(args, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while not (out / "img0.png").exists() and time.time() < deadline and process.poll() is None:
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    if process.returncode == 0:
        pytest.skip("the batch finished before the signal")
    assert process.returncode == 130, stderr
    assert stderr.count("\n") == 1 and "stopped by SIGINT" in stderr
    written = sorted(os.listdir(out))
    assert not [name for name in written if name.endswith(".tmp")]
    done = {name.rsplit(".", 1)[0] for name in written}
    assert all(f"{stem}.csv" in written and f"{stem}.png" in written for stem in done)  # both or neither
    np.loadtxt(out / "img0.csv", delimiter=",", skiprows=1)  # whole
    result = subprocess.run(args[:-1], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert f"{4 - len(done)} done, {len(done)} skipped" in result.stderr
    assert len(os.listdir(out)) == 8


def test_local_cluster_writes_the_same_files(images, tmp_path):
    """A real Dask ``LocalCluster`` (two worker processes): the same bytes as the local batch, failures reported."""
    distributed = pytest.importorskip("distributed")
    bad = images[0].parent / "bad.png"
    bad.write_text("not an image")
    local = tmp_path / "local"
    assert run(["batch", *images, "-d", local, *SMALL, "--format", "csv,svg", "-q"]).exit_code == 0
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        remote = tmp_path / "remote"
        args = ["batch", *images, bad, "-d", remote, *SMALL, "--format", "csv,svg"]
        result = run([*args, "--scheduler", cluster.scheduler_address])
        assert result.exit_code == FAILED_BASE + 1, result.output
        (line,) = failure_lines(result)
        assert line.startswith(f"stipple batch: {bad}: ")
        assert sorted(os.listdir(remote)) == sorted(os.listdir(local))
        for name in os.listdir(local):
            assert (remote / name).read_bytes() == (local / name).read_bytes(), name
        before = mtimes(remote)
        result = run([*args, "--scheduler", cluster.scheduler_address])
        assert "0 done, 3 skipped (outputs exist), 1 failed of 4" in result.stderr
        assert mtimes(remote) == before


def test_batch_says_which_images_left_pen_dots_out(tmp_path):
    """Each image's drawing that left dots out says so (the SVG's comment alone did), unless --quiet."""
    rows, columns = np.mgrid[0:30, 0:45]
    Image.fromarray((255 * (0.05 + 0.3 * columns / 45)).astype(np.uint8)).save(tmp_path / "dark.png")
    arguments = ["batch", str(tmp_path / "dark.png"), "-M", "3000", "--dot-style", "point", "--pen-width", "0.5mm"]
    arguments += ["--width", "30mm", "--iterations", "5", "--format", "svg", "-d", str(tmp_path / "out")]
    said = CliRunner().invoke(main, arguments)
    assert said.exit_code == 0, said.output
    (line,) = [line for line in said.output.splitlines() if "left out" in line]
    assert line.startswith("stipple batch: ") and "dark.png: note: " in line and "of 3000 dots left out" in line
    quiet = CliRunner().invoke(main, [*arguments, "--force", "-q"])
    assert quiet.exit_code == 0 and "left out" not in quiet.output


@pytest.mark.parametrize("transfer", [["--range", "0", "1"], ["--levels", "auto"]])
def test_a_batch_of_images_and_maps_gives_each_its_own_transfer(tmp_path, transfer):
    """--range is the maps', --levels the images': one input refuses the other's, a mixed batch must not."""
    Image.fromarray(np.tile(np.linspace(0, 255, 24).astype(np.uint8), (16, 1))).save(tmp_path / "a.png")
    np.save(tmp_path / "b.npy", np.linspace(0.0, 1.0, 16 * 24).reshape(16, 24))
    arguments = ["batch", str(tmp_path / "a.png"), str(tmp_path / "b.npy"), *transfer, "-M", "60", "-N", "12"]
    result = CliRunner().invoke(main, [*arguments, "--iterations", "2", "--format", "csv", "-d", str(tmp_path / "o")])
    assert result.exit_code == 0, result.output
    assert sorted(os.listdir(tmp_path / "o")) == ["a.csv", "b.csv"]


def test_batch_neither_offers_nor_takes_an_automatic_count(tmp_path):
    """Its help offered '-M INTEGER|AUTO' and the run then refused 'auto' (a held-out review)."""
    help_text = CliRunner().invoke(main, ["batch", "--help"]).output
    assert "INTEGER|AUTO" not in help_text and "-M auto is for stipple torus" in " ".join(help_text.split())
    result = CliRunner().invoke(main, ["batch", str(tmp_path / "a.png"), "-d", str(tmp_path / "out"), "-M", "auto"])
    assert result.exit_code == 2 and "'auto' is not a whole number in decimal digits" in result.output
    assert not (tmp_path / "out").exists()


def test_a_pipe_among_the_images_is_refused_before_any_work(images, tmp_path):
    """A FIFO among a shell glob's names waited for a writer, and the whole batch with it (a hostile review)."""
    import subprocess

    os.mkfifo(tmp_path / "pipe.png")
    command = [sys.executable, "-m", "stipple", "batch", *map(str, images), str(tmp_path / "pipe.png")]
    command += ["-d", str(tmp_path / "out"), *map(str, SMALL), "-q"]
    result = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert result.returncode == 1 and "pipe.png: not a regular file" in result.stderr, result.stderr
    assert not (tmp_path / "out").exists()
