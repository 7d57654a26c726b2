"""Real ``stipple`` processes killed mid-run and resumed reach the same points as an uninterrupted run."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
IMAGE = ROOT / "samples" / "camera128.png"
RUN = ["torus", str(IMAGE), "-M", "3000", "-N", "160", "--iterations", "1500", "--tol", "1e-14", "-q"]


def stipple(args, **kwargs):
    return subprocess.run([sys.executable, "-m", "stipple", *args], capture_output=True, text=True, cwd=ROOT, **kwargs)


def start(args):
    return subprocess.Popen(
        [sys.executable, "-m", "stipple", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT
    )


def wait_for_checkpoints(path, count, process, timeout=60):
    """Wait until ``count`` distinct versions of the checkpoint file have been seen (inode and mtime)."""
    seen = set()
    deadline = time.monotonic() + timeout
    while len(seen) < count and time.monotonic() < deadline and process.poll() is None:
        try:
            status = os.stat(path)
            seen.add((status.st_ino, status.st_mtime_ns))
        except FileNotFoundError:
            pass
        time.sleep(0.005)
    assert process.poll() is None, "the run ended before it could be interrupted; make it longer"
    assert len(seen) >= count


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    output = tmp_path_factory.mktemp("reference") / "dots.csv"
    result = stipple(RUN + ["-o", str(output)])
    assert result.returncode == 0, result.stderr
    return output.read_bytes()


def test_sigkill_then_resume_gives_identical_points(tmp_path, uninterrupted):
    checkpoint = tmp_path / "run.npz"
    process = start(RUN + ["--checkpoint", str(checkpoint), "--checkpoint-every", "3", "-o", str(tmp_path / "x.csv")])
    wait_for_checkpoints(checkpoint, 4, process)
    process.send_signal(signal.SIGKILL)
    process.wait()
    assert not (tmp_path / "x.csv").exists()
    resumed = stipple(RUN + ["--checkpoint", str(checkpoint), "--resume", "-o", str(tmp_path / "dots.csv")])
    assert resumed.returncode == 0, resumed.stderr
    assert (tmp_path / "dots.csv").read_bytes() == uninterrupted


@pytest.mark.parametrize("number,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_writes_checkpoint_and_outputs_then_resumes(tmp_path, uninterrupted, number, code):
    checkpoint = tmp_path / "run.npz"
    partial = tmp_path / "partial.csv"
    process = start(RUN + ["--checkpoint", str(checkpoint), "--checkpoint-every", "20", "-o", str(partial)])
    wait_for_checkpoints(checkpoint, 2, process)
    process.send_signal(number)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == code
    assert stderr.count("\n") == 1 and "resume with: stipple torus" in stderr and "--resume" in stderr
    assert len(partial.read_text().splitlines()) == 3001
    resumed = stipple(RUN + ["--checkpoint", str(checkpoint), "--resume", "-o", str(tmp_path / "dots.csv")])
    assert resumed.returncode == 0, resumed.stderr
    assert (tmp_path / "dots.csv").read_bytes() == uninterrupted


def test_extending_a_finished_run_with_more_iterations(tmp_path):
    base = ["sphere", "builtin:gaussians", "-M", "400", "-N", "24", "--tol", "1e-14", "-q", "--threads", "1"]
    checkpoint = tmp_path / "run.npz"
    assert stipple(base + ["--iterations", "30", "--checkpoint", str(checkpoint), "-o", "-"]).returncode == 0
    extended = stipple(base + ["--iterations", "60", "--checkpoint", str(checkpoint), "--resume", "-o", "-"])
    straight = stipple(base + ["--iterations", "60", "-o", "-"])
    assert extended.returncode == 0 and extended.stdout == straight.stdout


def test_multithreaded_torus_is_bit_reproducible():
    """With the near field, two threads run the transforms and the pairs at once, one thread each: the bits of one
    thread. Four give each two: the type-1 transforms split by residue class of the modes and the pairs in blocks,
    the same bits on every run."""
    from stipple import halftone_torus, load_density

    weights = load_density(IMAGE)

    def points(threads):
        return halftone_torus(weights, 3000, 160, iterations=60, tol=1e-14, threads=threads).points

    runs = [points(4) for _ in range(3)]
    assert np.array_equal(runs[0], runs[1]) and np.array_equal(runs[0], runs[2])
    single = points(1)
    assert np.array_equal(points(2), single)
    assert not np.array_equal(runs[0], single), "threads=4 did not take the split path"


def test_a_run_stopped_during_its_coarse_levels_leaves_no_checkpoint(tmp_path):
    """A signal during the coarse-to-fine start stops the levels half-way: their split is not the uninterrupted
    run's start, so a checkpoint of it would resume to other points. None is written; one stopped in the main run
    is (the control)."""
    from stipple import load_density
    from stipple.halftone import run
    from stipple.torus import torus_problem

    problem = torus_problem(load_density(IMAGE), 8000, threads=1)
    during_levels = run(problem, checkpoint=tmp_path / "levels.npz", callback=lambda state: True)
    assert during_levels.status == "stopped" and during_levels.iterations == 0
    assert not (tmp_path / "levels.npz").exists()
    states = []

    def stop_in_main_run(state):
        states.append(state.iteration)
        return len(states) > 1 and states[-1] < states[-2]  # the main run restarts the count: stop at its first

    in_main_run = run(problem, checkpoint=tmp_path / "main.npz", callback=stop_in_main_run)
    assert in_main_run.status == "stopped" and (tmp_path / "main.npz").exists()


def test_the_resume_hint_is_given_only_when_a_checkpoint_was_written(tmp_path, monkeypatch, capsys):
    from types import SimpleNamespace

    from stipple.cli.supervise import finish

    result = SimpleNamespace(iterations=0)
    options = {"checkpoint": str(tmp_path / "run.npz"), "resume": False, "quiet": False}
    monkeypatch.setattr(sys, "argv", ["stipple", "torus", "a.png", "--checkpoint", options["checkpoint"]])
    for written in (False, True):
        if written:
            (tmp_path / "run.npz").write_bytes(b"")
        with pytest.raises(SystemExit) as stopped:
            finish(result, signal.SIGINT, options, time.perf_counter())
        assert stopped.value.code == 130
        message = capsys.readouterr().err
        assert ("resume with: stipple torus" in message) is written
        assert ("nothing to resume" in message) is not written
