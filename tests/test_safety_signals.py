"""SIGINT / SIGTERM / SIGHUP while outputs are written: exit 130 / 143 / 129, one line, no temporary file,
nothing half-written."""

import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from safety_helpers import FAST, ROOT, leftovers, make_image, snapshot

# Runs the real CLI in a child process that sends itself SIGNAL right after the N-th fsync (temporary
# file written) or the N-th rename (N: comma-separated numbers): real signals at the moments that used
# to leak files.
CHILD = """
import os, signal, sys
from stipple.cli import main
name, numbers, kind = sys.argv[1], [int(n) for n in sys.argv[2].split(",")], sys.argv[3]
real = getattr(os, name)
calls = []
def hooked(*args):
    result = real(*args)
    calls.append(1)
    if len(calls) in numbers:
        os.kill(os.getpid(), getattr(signal, kind))
    return result
setattr(os, name, hooked)
sys.argv = ["stipple"] + sys.argv[4:]
main(prog_name="stipple")
"""

OUTPUTS = ["-o", "a.csv", "-o", "b.svg", "-o", "c.png"]


@pytest.fixture
def folder(tmp_path):
    make_image(tmp_path / "in.png")
    for name in ("a.csv", "b.svg", "c.png"):
        (tmp_path / name).write_text(f"old {name}\n")
    return tmp_path


def child(folder, hook, numbers, kind, args):
    return subprocess.run(
        [sys.executable, "-c", CHILD, hook, str(numbers), kind, *args], cwd=folder, capture_output=True, text=True
    )


# SIGHUP: a closed terminal or a dropped SSH session (it left eight temporaries and a lock: a hostile review).
@pytest.mark.parametrize("kind,code", [("SIGINT", 130), ("SIGTERM", 143), ("SIGHUP", 129)])
@pytest.mark.parametrize("number", [1, 3])
def test_signal_while_temporaries_are_written(folder, kind, code, number):
    before = snapshot(folder)
    result = child(folder, "fsync", number, kind, ["torus", "in.png", *FAST, *OUTPUTS])
    assert result.returncode == code, result.stderr
    assert result.stderr.strip().splitlines() == [
        f"stipple: stopped by {kind}; outputs are whole or untouched, no temporary file left"
    ]
    assert snapshot(folder) == before and leftovers(folder) == []


@pytest.mark.parametrize("kind,code", [("SIGINT", 130), ("SIGTERM", 143), ("SIGHUP", 129)])
def test_signal_during_the_renames_waits_until_all_are_done(folder, kind, code):
    result = child(folder, "replace", 1, kind, ["torus", "in.png", *FAST, *OUTPUTS])
    assert result.returncode == code, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    assert all((folder / name).read_bytes() != f"old {name}\n".encode() for name in ("a.csv", "b.svg", "c.png"))
    assert leftovers(folder) == []


@pytest.mark.parametrize("kind,code", [("SIGINT", 130), ("SIGTERM", 143)])
def test_second_signal_while_the_checkpoint_is_written(folder, kind, code):
    """The first signal (after the second checkpoint) asks the run to stop; the second arrives while the
    final checkpoint's temporary file is written: it is removed and the second checkpoint stays whole."""
    args = ["torus", "in.png", *FAST[:4], "--iterations", "50", "-q", "--checkpoint", "run.npz"]
    before = snapshot(folder)
    result = child(folder, "fsync", "2,3", kind, [*args, "--checkpoint-every", "1", *OUTPUTS])
    assert result.returncode == code, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    assert leftovers(folder) == []
    after = snapshot(folder)
    assert {name: after[name] for name in before} == before
    with np.load(folder / "run.npz") as archive:
        assert int(archive["iteration"]) == 2


def test_two_quick_signals_in_a_run_leave_a_whole_checkpoint(folder):
    image = ROOT / "samples" / "camera128.png"
    args = [
        "torus",
        str(image),
        "-M",
        "2000",
        "-N",
        "128",
        "--iterations",
        "100000",
        "--tol",
        "1e-14",
        "-q",
        "--checkpoint",
        "run.npz",
        "--checkpoint-every",
        "1",
        *OUTPUTS,
    ]
    before = snapshot(folder)
    process = subprocess.Popen([sys.executable, "-m", "stipple", *args], cwd=folder, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not (folder / "run.npz").exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    process.send_signal(signal.SIGINT)
    time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    stderr = process.communicate(timeout=60)[1]
    assert process.returncode == 130, stderr
    assert len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr
    assert leftovers(folder) == []
    with np.load(folder / "run.npz") as archive:
        assert archive["points"].shape == (2000, 2)
    after = snapshot(folder)
    changed = {name for name in ("a.csv", "b.svg", "c.png") if after[name] != before[name]}
    assert changed in (set(), {"a.csv", "b.svg", "c.png"})


def test_a_second_signal_after_the_first_is_ignored_on_the_way_out():
    """A batch stopped by SIGINT printed a KeyboardInterrupt traceback now and then: ``timeout`` signals the
    process and its group, and the second signal came while Python waited for the pool's threads at exit."""
    from stipple.cli.supervise import SignalGuard
    from stipple.io.commit import taken_signals

    # Every signal the guard takes is put back: left ignored in this process, it was ignored by the children of
    # the tests after this one (a pipe-reading child then sat through its SIGTERM).
    previous = {number: signal.getsignal(number) for number in taken_signals()}
    try:
        guard = SignalGuard()
        with guard, guard.deferred():
            guard.stop_requested(None)  # the optimiser has reported: a first signal is deferred from now on
            guard._handle(signal.SIGINT, None)  # the first signal, as the handler receives it
        assert signal.getsignal(signal.SIGINT) == signal.SIG_IGN
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
    with SignalGuard():  # no signal: the handler from before is back
        pass
    assert signal.getsignal(signal.SIGINT) == previous[signal.SIGINT]


def test_a_run_under_nohup_ignores_sighup(folder):
    """nohup ignores SIGHUP before the program starts: the guard took it back, and a logout stopped the run
    (exit 129, the outputs of the iterations so far) where it used to go on (a code review)."""
    script = "import signal\nsignal.signal(signal.SIGHUP, signal.SIG_IGN)\n" + CHILD
    args = ["fsync", "1", "SIGHUP", "torus", "in.png", *FAST, *OUTPUTS]
    result = subprocess.run([sys.executable, "-c", script, *args], cwd=folder, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert leftovers(folder) == [] and (folder / "a.csv").read_text().startswith("x,y")


LOADING = """
import builtins, os, signal, sys
real = builtins.__import__
def hooked(name, *args, **kwargs):
    if name == sys.argv[1] and not getattr(hooked, "sent", False):
        hooked.sent = True
        os.kill(os.getpid(), signal.SIGINT)
    return real(name, *args, **kwargs)
builtins.__import__ = hooked
from stipple.cli import main
sys.argv = ["stipple"] + sys.argv[2:]
main(prog_name="stipple")
"""


@pytest.mark.parametrize("module", ["click", "numpy"])
def test_ctrl_c_while_the_commands_load_is_one_line(folder, module):
    """Ctrl-C in the first 0.2 s, while ``stipple.cli`` imports click and numpy, gave a KeyboardInterrupt's
    traceback (a hostile sweep): now the stopped run's line and 130, nothing written."""
    before = snapshot(folder)
    args = [module, "torus", "in.png", *FAST, *OUTPUTS]
    result = subprocess.run([sys.executable, "-c", LOADING, *args], cwd=folder, capture_output=True, text=True)
    assert result.returncode == 130, result.stderr
    assert result.stderr.strip().splitlines() == [
        "stipple: stopped by SIGINT; outputs are whole or untouched, no temporary file left"
    ]
    assert snapshot(folder) == before and leftovers(folder) == []


def test_loading_the_commands_gives_back_the_callers_sigint_handler():
    """The handler is the command line's only while it loads: a test runner or a library keeps its own."""
    script = "import signal\nimport stipple.cli\nprint(signal.getsignal(signal.SIGINT) is signal.default_int_handler)"
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert result.stdout.strip() == "True", result.stderr
