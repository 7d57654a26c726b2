"""Holes a hostile sweep found (2026-11-27): a pipe read before the run swallowed the first signal, outputs
replaced pipes and devices, a closed stderr, thread counts in the environment, an unbounded Floyd-Steinberg
baseline and ``--init`` ignored by ``--resume``. Each test fails on the code before."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from safety_helpers import FAST, leftovers, make_image

from stipple.measures.picture import MAX_DITHER_PIXELS, floyd_steinberg

STIPPLE = [sys.executable, "-m", "stipple"]


def stipple(*args, cwd, **keywords):
    return subprocess.run([*STIPPLE, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=120, **keywords)


def wait_for_the_pipe(pid, seconds=30.0):
    """Until the process waits for a writer to open its FIFO (Linux's wait channel), or ``seconds`` have passed."""
    deadline = time.monotonic() + seconds
    channel = f"/proc/{pid}/wchan"
    while time.monotonic() < deadline:
        try:
            with open(channel) as stream:
                if "wait_for_partner" in stream.read():
                    return
        except OSError:
            time.sleep(2.0)  # no such file: no /proc here
            return
        time.sleep(0.05)


def taking_signals():
    """The child's SIGINT and SIGTERM at their defaults: a test run in this process may leave them ignored (the
    signal guard ignores them after a signal), and a child would inherit that, as from ``nohup``."""
    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, signal.SIG_DFL)


@pytest.mark.parametrize("kind,code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_one_signal_stops_a_run_still_waiting_for_its_input(tmp_path, kind, code):
    """A FIFO with no writer yet: the read happened where the first signal only asked the run to stop after its
    next iteration, so ``timeout`` had to kill it."""
    os.mkfifo(tmp_path / "in.png")
    process = subprocess.Popen(
        [*STIPPLE, "torus", "in.png", *FAST, "-o", "a.csv"],
        cwd=tmp_path,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=taking_signals,
    )
    wait_for_the_pipe(process.pid)
    process.send_signal(kind)
    try:
        stderr = process.communicate(timeout=20)[1]
    finally:
        process.kill()
    assert process.returncode == code, stderr
    assert len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr
    assert not (tmp_path / "a.csv").exists() and leftovers(tmp_path) == []


def test_an_output_that_is_a_pipe_a_device_or_a_link_to_one_is_refused_and_kept(tmp_path):
    """Renamed over them, the finished file replaced a named pipe (its reader got nothing) and a device node."""
    make_image(tmp_path / "in.png")
    os.mkfifo(tmp_path / "pipe.csv")
    os.symlink(os.devnull, tmp_path / "null.csv")
    for name, kind in (("pipe.csv", "a named pipe"), ("null.csv", "a device")):
        done = stipple("torus", "in.png", *FAST, "-o", name, cwd=tmp_path)
        assert done.returncode == 1 and f"cannot write (it is {kind}, not a regular file)" in done.stderr, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1
    assert (tmp_path / "pipe.csv").is_fifo() and os.path.islink(tmp_path / "null.csv")
    assert os.path.exists(os.devnull) and not os.path.isfile(os.devnull) and leftovers(tmp_path) == []


def test_a_closed_stderr_neither_fails_the_run_nor_reaches_its_outputs(tmp_path):
    """With file descriptor 2 closed the first file opened took its number; the run failed without a word."""
    make_image(tmp_path / "in.png")
    args = ["torus", "in.png", "-M", "30", "-N", "8", "--iterations", "2", "-o", "a.csv"]
    done = subprocess.run(
        [*STIPPLE, *args], cwd=tmp_path, stdout=subprocess.PIPE, preexec_fn=lambda: os.close(2), timeout=120
    )
    assert done.returncode == 0
    lines = (tmp_path / "a.csv").read_text().splitlines()
    assert lines[0] == "x,y" and len(lines) == 31


@pytest.mark.parametrize("value", ["-1", "abc", "", "4,2", "1.5", "²"])
def test_a_thread_count_in_the_environment_that_is_no_whole_number_gets_one_line(tmp_path, value):
    make_image(tmp_path / "in.png")
    done = stipple("torus", "in.png", *FAST, "-o", "a.csv", cwd=tmp_path, env={**os.environ, "OMP_NUM_THREADS": value})
    assert done.returncode == 1 and "OMP_NUM_THREADS must be a whole number" in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "a.csv").exists()
    helped = stipple("torus", "--help", cwd=tmp_path, env={**os.environ, "OMP_NUM_THREADS": value})
    assert helped.returncode == 0
    signed = stipple("torus", "in.png", *FAST, "-o", "a.csv", cwd=tmp_path, env={**os.environ, "OMP_NUM_THREADS": "+1"})
    assert signed.returncode == 0, signed.stderr  # what ducc0 takes is taken


def test_the_floyd_steinberg_baseline_is_bounded():
    """10^8 dots of a 48 x 32 picture grew the dithered image to 2.4 GB; now at most MAX_DITHER_PIXELS pixels, and
    fewer dots than asked come back. An ordinary count is met as before."""
    reference = np.tile(np.linspace(0, 1, 48), (32, 1))
    picture, dots = floyd_steinberg(reference, 10**8)
    assert picture.shape == reference.shape and 0 < dots <= MAX_DITHER_PIXELS
    assert dots > 0.4 * MAX_DITHER_PIXELS  # the largest image the bound allows, half of it ink
    picture, dots = floyd_steinberg(reference, 700)
    assert abs(dots - 700) <= 10


def test_the_command_line_refuses_more_baseline_dots_than_a_run_may_have(tmp_path):
    make_image(tmp_path / "in.png")
    done = stipple("evaluate", "in.png", "in.png", "--floyd-steinberg", "100000000", cwd=tmp_path)
    assert done.returncode == 2 and "--floyd-steinberg" in done.stderr and "Traceback" not in done.stderr


def test_init_with_resume_is_refused(tmp_path):
    """A resumed run continues from its checkpoint's points: the --init it was given was silently ignored."""
    make_image(tmp_path / "in.png")
    args = ["torus", "in.png", "-M", "30", "-N", "8", "-q", "--checkpoint", "run.npz", "-o", "a.csv"]
    assert stipple(*args, "--iterations", "2", cwd=tmp_path).returncode == 0
    np.savetxt(
        tmp_path / "start.csv", np.random.default_rng(0).random((30, 2)) * 10, delimiter=",", header="x,y", comments=""
    )
    kept = (tmp_path / "a.csv").read_bytes()
    done = stipple(*args, "--iterations", "4", "--resume", "--init", "start.csv", cwd=tmp_path)
    assert done.returncode == 1 and "--init is for a new run" in done.stderr, done.stderr
    assert (tmp_path / "a.csv").read_bytes() == kept
    assert stipple(*args, "--iterations", "4", "--resume", cwd=tmp_path).returncode == 0
