"""Hostile inputs that used to end in a traceback: each is one line on stderr, exit 1 (data) or 2 (usage)."""

import json
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from safety_helpers import FAST, invoke, make_image, refused, snapshot

import stipple.io.sources

RESUME = ["torus", "in.png", "-M", "30", "-N", "8", "--iterations", "4", "-q", "--resume", "-o", "out.csv"]


@pytest.fixture
def folder(tmp_path):
    make_image(tmp_path / "in.png")
    (tmp_path / "out.csv").write_text("previous output\n")
    (tmp_path / "p.csv").write_text("x,y\n1.5,2.5\n3.5,7.5\n9.5,4.5\n")
    return tmp_path


def npy_with_header(path, header, payload=b"\0" * 64):
    """A version-1 .npy file with the given header dict text and payload."""
    text = header + " " * (63 - (10 + len(header)) % 64) + "\n"
    path.write_bytes(b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text.encode() + payload)
    return path


def test_npy_header_declaring_seven_tebibytes(folder):
    npy_with_header(folder / "huge.npy", "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000, 1000000), }")
    refused(["torus", "huge.npy", *FAST, "-o", "out.csv"], folder, "header declares shape (1000000, 1000000)")


def test_endless_image_input_is_capped(folder, monkeypatch):
    monkeypatch.setattr(stipple.io.sources, "MAX_INPUT_BYTES", 1 << 20)
    refused(["torus", "/dev/zero", *FAST, "-o", "out.csv"], folder, "/dev/zero: input is longer than the 1048576")


def test_endless_points_input_is_capped(folder, monkeypatch):
    monkeypatch.setattr(stipple.io.sources, "MAX_INPUT_BYTES", 1 << 20)
    refused(["render", "/dev/zero", "-o", "out.csv"], folder, "input is longer than")


def test_oversized_regular_file_is_refused_before_reading(folder, monkeypatch):
    monkeypatch.setattr(stipple.io.sources, "MAX_INPUT_BYTES", 20)
    refused(["torus", "in.png", *FAST, "-o", "out.csv"], folder, "more than the 20 bytes read at most")


CONFIGS = {
    "endless config": ("/dev/zero", None, "longer than 1048576 bytes"),
    "non-UTF-8 config": ("bad.toml", b"points = 30\n# \xff\xfe\n", "is not UTF-8 text"),
    "points = 1e400": ("inf.toml", b"points = 1e400\n", "key 'points' in inf.toml: expected an integer, not inf"),
    "nested arrays": ("deep.toml", b"range = " + b"[" * 5000 + b"]" * 5000 + b"\n", "deep.toml"),
    "tol = nan": ("nan.toml", b"tol = nan\n", "expected a finite number, not nan"),
}


@pytest.mark.parametrize("name,data,message", CONFIGS.values(), ids=CONFIGS.keys())
def test_bad_config_files(folder, name, data, message):
    if data is not None:
        (folder / name).write_bytes(data)
    refused(["torus", "in.png", "--config", name, "-q", "-o", "out.csv"], folder, message, code=2)


OPTIONS = {
    "--seed -1": (["torus", "in.png", *FAST, "--seed", "-1"], "seed must be an integer in [0,"),
    "--lon0 nan": (["sphere", "--uniform", "-M", "30", "-N", "4", "-q", "--lon0", "nan"], "lon0 must be a longitude"),
    "--lon0 inf in evaluate": (["evaluate", "s.csv", "--uniform", "-N", "4", "--lon0", "inf"], "lon0 must be"),
    "render 1e308 to PNG": (["render", "big.csv", "-o", "b.png"], "x,y must be pixel positions below"),
    "render 1e308 --order": (["render", "big.csv", "--size", "16,12", "--order", "-o", "b.svg"], "pixel positions"),
    "evaluate one point": (["evaluate", "one.csv", "in.png"], "evaluate needs at least 2 points, not 1"),
    "evaluate one sphere point": (["evaluate", "s1.csv", "--uniform", "-N", "4"], "at least 2 points"),
    "tall PNG canvas": (
        ["render", "p.csv", "--size", "2,100000", "--png-width", "1024", "-o", "t.png"],
        "more than 262144 per side",
    ),
    "wide PNG canvas": (["render", "p.csv", "--png-width", "32768", "-o", "t.png"], "smaller --png-width"),
    "wide PNG before a torus run": (["torus", "in.png", *FAST, "--png-width", "32768", "-o", "t.png"], "GiB of memory"),
    "wide PNG before a sphere run": (
        ["sphere", "--uniform", "-M", "30", "-N", "4", "--png-width", "32768", "-o", "t.png"],
        "GiB of memory",
    ),
    "huge --size": (["render", "p.csv", "--size", "99999999999,2", "-o", "t.svg"], "size must be WIDTH,HEIGHT"),
}


@pytest.mark.parametrize("args,message", OPTIONS.values(), ids=OPTIONS.keys())
def test_bad_numbers_and_point_sets(folder, args, message, monkeypatch):
    monkeypatch.setattr("stipple.allocator.available_memory", lambda: 2**34)  # the same answer on every machine
    (folder / "big.csv").write_text("x,y\n1e308,5\n2,3\n")
    (folder / "one.csv").write_text("x,y\n1.5,2.5\n")
    (folder / "s1.csv").write_text("lon,lat\n10,20\n")
    (folder / "s.csv").write_text("lon,lat\n10,20\n30,-40\n")
    refused(args, folder, message)


@pytest.mark.parametrize("command", [["torus", "in.png", *FAST], ["evaluate", "p.csv", "in.png"]])
def test_stdout_on_a_full_device(folder, command):
    before = snapshot(folder)
    with open("/dev/full", "w") as full:
        result = subprocess.run(
            [sys.executable, "-m", "stipple", *command], cwd=folder, stdout=full, stderr=subprocess.PIPE, text=True
        )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == ["Error: cannot write to stdout (No space left on device)"]
    assert snapshot(folder) == before


@pytest.fixture
def checkpoint(folder):
    """The arrays of a real 2-iteration checkpoint of the folder's image, and a function saving a variant."""
    assert invoke(["torus", "in.png", *FAST, "--checkpoint", "good.npz", "-o", "first.csv"], folder).exit_code == 0
    with np.load(folder / "good.npz") as archive:
        contents = dict(archive)

    def save(**changes):
        np.savez(folder / "bad.npz", **{**contents, **changes})

    return contents, save


def metadata_with(contents, **changes):
    return np.asarray(json.dumps({**json.loads(str(contents["metadata"])), **changes}))


def settings_with(contents, **changes):
    return {**json.loads(str(contents["metadata"]))["settings"], **changes}


TAMPERED = {
    "complex points": (lambda c: {"points": c["points"] + 0j}, "points: .npy must hold floating-point numbers"),
    "string points": (lambda c: {"points": c["points"].astype("U1")}, "must hold floating-point numbers"),
    "long string points": (lambda c: {"points": c["points"].astype(str)}, "member points holds"),
    "short direction": (lambda c: {"direction": c["direction"][:5]}, "direction has shape (5, 2), not (30, 2)"),
    "transposed gradient": (lambda c: {"gradient": c["gradient"].T}, "gradient has shape (2, 30)"),
    "2-D energies": (lambda c: {"energies": c["energies"][None, :]}, "energies has shape (1, 3), not (3,)"),
    "float iteration": (lambda c: {"iteration": np.asarray(2.5)}, "iteration: .npy must hold an integer"),
    "array iteration": (lambda c: {"iteration": np.arange(2)}, "iteration has shape (2,), not ()"),
    "NaN curvature": (lambda c: {"direction_curvature": np.asarray(np.nan)}, "direction_curvature is nan"),
    "points off the torus": (lambda c: {"points": c["points"] + 5}, "points are not in [0, 1]"),
    "numeric metadata": (lambda c: {"metadata": np.arange(3.0)}, "metadata: .npy must hold a text string"),
    "nested JSON": (lambda c: {"metadata": np.asarray("[" * 100000 + "]" * 100000)}, "corrupt checkpoint metadata"),
    "nested settings": (
        lambda c: {"metadata": metadata_with(c, settings=settings_with(c, points=json.loads("[" * 500 + "]" * 500)))},
        "points was [[[[",
    ),
    "version as text": (lambda c: {"metadata": metadata_with(c, version="1")}, "format version '1'"),
    "rng state as number": (lambda c: {"metadata": metadata_with(c, rng_state=5)}, "rng_state is not a string"),
}


@pytest.mark.parametrize("change,message", TAMPERED.values(), ids=TAMPERED.keys())
def test_tampered_checkpoint_members(folder, checkpoint, change, message):
    contents, save = checkpoint
    save(**change(contents))
    refused([*RESUME, "--checkpoint", "bad.npz"], folder, message)


def test_a_two_gigabyte_member_is_not_inflated(folder, checkpoint):
    """A member whose directory entry claims 2 GiB is refused from the entry alone."""
    contents, _ = checkpoint
    with zipfile.ZipFile(folder / "bad.npz", "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, array in contents.items():
            if name != "points":
                with archive.open(f"{name}.npy", "w") as stream:
                    np.lib.format.write_array(stream, array, allow_pickle=False)
        archive.writestr("points.npy", b"\0" * (1 << 20))
    data = bytearray((folder / "bad.npz").read_bytes())
    entry = data.index(b"PK\x01\x02")  # central directory entries; the name starts at byte 46
    while data[entry + 46 : entry + 56] != b"points.npy":
        entry = data.index(b"PK\x01\x02", entry + 4)
    data[entry + 24 : entry + 28] = (2**31).to_bytes(4, "little")  # uncompressed size in the central directory
    (folder / "bad.npz").write_bytes(bytes(data))
    refused([*RESUME, "--checkpoint", "bad.npz"], folder, "member points holds 2147483648 bytes")


def refused_with_a_closed_stream(folder, command, stream, message):
    """``stipple command`` run with file descriptor ``stream`` closed: one line, exit 1, nothing written."""
    import os

    before = snapshot(folder)
    result = subprocess.run(
        [sys.executable, "-m", "stipple", *command],
        cwd=folder,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: os.close(stream),
    )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [message]
    assert snapshot(folder) == before


@pytest.mark.parametrize("command", [["torus", "in.png", *FAST], ["evaluate", "p.csv", "in.png"]])
def test_closed_stdout_is_refused_before_the_work(folder, command):
    refused_with_a_closed_stream(folder, command, 1, "Error: cannot write to stdout: it is closed")


@pytest.mark.parametrize(
    "command",
    [["torus", "-", *FAST, "-o", "o.csv"], ["evaluate", "-", "in.png"], ["torus", "in.png", *FAST, "--init", "-"]],
)
def test_closed_stdin_is_one_line(folder, command):
    """'-' with standard input closed (``<&-``) ended in an AttributeError traceback."""
    refused_with_a_closed_stream(folder, command, 0, "Error: cannot read '-' (stdin): it is closed")


@pytest.mark.parametrize("command", [["torus", "in.png", *FAST, "-o", "-"], ["design", "-t", "3", "-o", "d.csv"]])
def test_a_checkpoint_on_stdout_is_refused(folder, command):
    """``--checkpoint -`` wrote the zip to stdout, glued to the CSV, and could not be resumed."""
    refused([*command, "--checkpoint", "-"], folder, "--checkpoint must name a file, not '-'")
