"""One run per checkpoint: a second run on the same checkpoint is refused while the first holds it."""

import os
import subprocess
import sys
import time

import numpy as np
import pytest
from safety_helpers import FAST, ROOT, invoke, leftovers, make_image, refused

from stipple.io.safety import CheckpointLock


@pytest.fixture
def folder(tmp_path):
    make_image(tmp_path / "in.png")
    return tmp_path


def test_a_held_checkpoint_refuses_a_fresh_run(folder):
    with CheckpointLock(folder / "run.npz"):
        refused(
            ["torus", "in.png", *FAST, "--checkpoint", "run.npz", "-o", "a.csv"],
            folder,
            "run.npz: checkpoint is in use",
        )
    assert not (folder / "run.npz").exists()


def test_a_held_checkpoint_refuses_a_resume_and_stays_whole(folder):
    assert invoke(["torus", "in.png", *FAST, "--checkpoint", "run.npz", "-o", "a.csv"], folder).exit_code == 0
    args = [
        "torus",
        "in.png",
        *FAST[:4],
        "--iterations",
        "4",
        "-q",
        "--checkpoint",
        "run.npz",
        "--resume",
        "-o",
        "a.csv",
    ]
    with CheckpointLock(folder / "run.npz"):
        refused(args, folder, "in use by another stipple run")
    assert invoke(args, folder).exit_code == 0
    assert leftovers(folder) == []


def test_the_lock_holds_for_every_spelling_of_the_path(folder):
    os.symlink("real.npz", folder / "link.npz")
    (folder / "sub").mkdir()
    with CheckpointLock(folder / "real.npz"):
        for spelling in ("link.npz", "sub/../real.npz", str(folder / "real.npz")):
            args = ["torus", "in.png", *FAST, "--checkpoint", spelling, "-o", "a.csv"]
            refused(args, folder, "checkpoint is in use by another stipple run")


def test_the_lock_is_exclusive_and_released():
    import tempfile

    with tempfile.TemporaryDirectory() as directory:
        path = f"{directory}/x.npz"
        with CheckpointLock(path) as first:
            with pytest.raises(ValueError, match="in use"):
                CheckpointLock(path).acquire()
            assert first.handle is not None
        with CheckpointLock(path):
            pass
        assert leftovers(directory) == []


RACE = ["torus", str(ROOT / "samples" / "camera128.png"), "-M", "2000", "-N", "128", "--tol", "1e-14", "-q"]

# Both children import everything first, then wait for the same go-file, so that they reach the lock
# within milliseconds of each other however loaded the machine is.
STARTER = """
import os, sys, time
import stipple.cli, stipple.torus, stipple.checkpoint, stipple.pipelines.image
go = sys.argv[1]
while not os.path.exists(go):
    time.sleep(0.001)
sys.argv = ["stipple"] + sys.argv[2:]
stipple.cli.main(prog_name="stipple")
"""


def test_two_processes_started_together_on_one_checkpoint(tmp_path):
    """Both start at once: exactly one runs, the other is refused naming the file; the checkpoint is the winner's."""
    checkpoint, go = tmp_path / "shared.npz", tmp_path / "go"
    processes = [
        subprocess.Popen(
            [
                sys.executable,
                "-c",
                STARTER,
                str(go),
                *RACE,
                "--time-limit",
                "2",
                "--iterations",
                "100000",
                "--seed",
                str(seed),
                "--checkpoint",
                str(checkpoint),
                "-o",
                str(tmp_path / f"dots{seed}.csv"),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=tmp_path,
        )
        for seed in (1, 2)
    ]
    time.sleep(1.0)  # let both finish importing (they wait for the go-file in any case)
    go.touch()
    results = [(process.wait(timeout=120), process.stderr.read()) for process in processes]
    codes = sorted(code for code, _ in results)
    assert codes == [0, 1], results
    winner = [seed for seed, (code, _) in zip((1, 2), results, strict=True) if code == 0][0]
    loser_message = [text for code, text in results if code == 1][0]
    assert f"{checkpoint}: checkpoint is in use by another stipple run" in loser_message
    assert len(loser_message.strip().splitlines()) == 1 and "Traceback" not in loser_message
    assert not (tmp_path / f"dots{3 - winner}.csv").exists()
    saved = np.load(checkpoint)["points"] * 128
    written = np.loadtxt(tmp_path / f"dots{winner}.csv", delimiter=",", skiprows=1)
    # The output is the checkpoint's points after the spread step (when the run settled in time), its few
    # iterations and the low-frequency correction: moved by a fraction of the spacing (about 3 px here), where
    # another run's points would be anywhere.
    assert np.max(np.abs((saved - written + 64) % 128 - 64)) < 1.0
    assert leftovers(tmp_path) == []
