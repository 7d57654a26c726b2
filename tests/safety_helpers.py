"""Shared checks of the safety tests: one line on stderr, no traceback, every file untouched, no temporaries."""

import subprocess
import sys
from pathlib import Path

import numpy as np
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main

ROOT = Path(__file__).resolve().parents[1]
FAST = ["-M", "30", "-N", "8", "--iterations", "2", "-q"]


def make_image(path, size=(16, 12)):
    """A small gray ramp image (dark on the left)."""
    width, height = size
    ramp = np.tile(np.linspace(0, 230, width).astype(np.uint8), (height, 1))
    Image.fromarray(ramp).save(path)
    return path


def snapshot(directory):
    """``{relative path: bytes}`` of every regular file under ``directory`` (symlinks are not followed)."""
    directory = Path(directory)
    return {
        str(path.relative_to(directory)): path.read_bytes()
        for path in sorted(directory.rglob("*"))
        if path.is_file() and not path.is_symlink()
    }


def leftovers(directory):
    """Temporary and lock files (relative paths) that stipple may have left under ``directory``."""
    directory = Path(directory)
    return [
        str(path.relative_to(directory))
        for path in directory.rglob(".*")
        if path.name.startswith(".stipple-") or path.name.endswith(".lock")
    ]


def check_refused(result, code, message, directory, before):
    """The run exited with ``code``, printed one line on stderr containing ``message`` and no traceback,
    changed no file under ``directory`` (``before`` is its snapshot) and left no temporary file."""
    stderr = result.stderr if hasattr(result, "stderr") else ""
    assert result_code(result) == code, stderr
    assert "Traceback" not in stderr and "Traceback" not in output_of(result)
    assert len(stderr.strip().splitlines()) == 1, stderr
    assert message in stderr, stderr
    after = snapshot(directory)
    assert {name: data for name, data in after.items() if name in before} == before
    assert set(after) <= set(before), sorted(set(after) - set(before))
    assert [name for name in leftovers(directory) if name not in before] == []


def result_code(result):
    return result.exit_code if hasattr(result, "exit_code") else result.returncode


def output_of(result):
    return result.output if hasattr(result, "output") else result.stdout or ""


def invoke(args, directory):
    """Run the CLI in this process with ``directory`` as the working directory."""
    import os

    previous = os.getcwd()
    os.chdir(directory)
    try:
        return CliRunner().invoke(main, [str(arg) for arg in args])
    finally:
        os.chdir(previous)


def refused(args, directory, message, code=1):
    """Run ``stipple args`` in ``directory`` and check it is refused cleanly with nothing changed."""
    before = snapshot(directory)
    check_refused(invoke(args, directory), code, message, directory, before)


def stipple_process(args, directory, **kwargs):
    """``stipple args`` as a real process (text output captured) in ``directory``."""
    return subprocess.run(
        [sys.executable, "-m", "stipple", *map(str, args)], cwd=directory, capture_output=True, text=True, **kwargs
    )
