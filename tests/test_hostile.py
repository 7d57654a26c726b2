"""Issue 33: the newer commands under careless and hostile use; one test per row of the issue's table (row 1, the
image storages, is tests/test_image_formats.py). Every network test binds to 127.0.0.1 only."""

import os
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from PIL import Image
from safety_helpers import check_refused, snapshot

from stipple import batch as batch_module

FAST = ["-M", "30", "-N", "8", "--iterations", "2", "-q"]


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
