"""Holes a third hostile sweep found (2026-11-27): an .npy header's tokenizer error, SVG drawings with infinite,
huge or deeply nested content, CSS colours out of range, a spectrum plot and the text report both on stdout, a
checkpoint whose domain is no name, a line's resume message, hidden files among a folder's frames, and a globe's
PNG that its memory check undercounted. Each test fails on the code before."""

import io
import json

import numpy as np
import pytest
from PIL import Image
from safety_helpers import FAST, invoke, make_image, refused

import stipple.allocator
from stipple.io.png import float_picture_layers
from stipple.io.video import open_frames


def npy_with_header(text):
    header = text.encode()
    padding = 64 - (10 + len(header) + 1) % 64
    return b"\x93NUMPY\x01\x00" + (len(header) + padding + 1).to_bytes(2, "little") + header + b" " * padding + b"\n"


def test_an_npy_header_with_an_unclosed_bracket_is_refused_in_one_line(tmp_path):
    """numpy's tokenizer raised TokenError, which the reader did not catch: a traceback of 79 lines."""
    (tmp_path / "bad.npy").write_bytes(npy_with_header("{'descr': ("))
    refused(["torus", "bad.npy", *FAST, "-o", "a.csv"], tmp_path, "corrupt or truncated .npy file (EOF in")


SVG = '<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm"{}>{}</svg>'


@pytest.mark.parametrize(
    "attributes, body, message",
    [
        (' viewBox="0 0 10 10"', '<path d="M0 0 L1e309 0"/>', "not a number or lies farther than"),
        (' viewBox="0 0 10 10"', '<path d="M0 0 L1e308 0 L-1e308 0"/>', "lies farther than 1e+07 mm"),
        ("", '<g transform="scale(1e308) scale(1e308)"><path d="M0 0 L1 0"/></g>', "not a number"),
        (' viewBox="0 0 10 10"', '<path d="M0 0 A 1e308 1e308 0 1 1 1 1"/>', "too large to draw"),
        ("", "<g>" * 5000 + '<path d="M0 0 L1 1"/>' + "</g>" * 5000, "nested more than 200 deep"),
        (' viewBox="0 0 nan 10"', '<path d="M0 0 L1 1"/>', "cannot read the viewBox"),
        ("", '<g transform="skewX()"><path d="M0 0 L1 1"/></g>', "cannot read the transform skewX()"),
        ("", '<rect x="nan" width="5" height="5"/>', "cannot read <rect x='nan'>"),
    ],
)
def test_a_drawing_with_infinite_huge_or_nested_content_is_refused_in_one_line(tmp_path, attributes, body, message):
    """Tracebacks of 36 to 2998 lines (NaN to int in the plot's clock, an arc's overflow, Python's recursion),
    or Python's own words ('list index out of range')."""
    (tmp_path / "d.svg").write_text(SVG.format(attributes, body))
    refused(["evaluate", "d.svg"], tmp_path, message)


@pytest.mark.parametrize("option", ["--color", "--background"])
@pytest.mark.parametrize("colour", ["rgb(999,2,3)", "hsl(720,200%,50%)"])
def test_a_colour_out_of_range_is_refused(tmp_path, option, colour):
    """Pillow passes them through: the SVG got fill="#3e70203"."""
    make_image(tmp_path / "in.png")
    refused(["torus", "in.png", *FAST, option, colour, "-o", "a.svg"], tmp_path, "channels from 0 to 255")


def test_a_spectrum_on_stdout_is_the_only_thing_there(tmp_path):
    """The text report followed the PNG's bytes on stdout."""
    make_image(tmp_path / "in.png")
    assert invoke(["torus", "in.png", *FAST, "-o", "a.csv"], tmp_path).exit_code == 0
    result = invoke(["evaluate", "a.csv", "in.png", "--spectrum", "-"], tmp_path)
    assert result.exit_code == 0
    data = result.stdout_bytes
    picture = Image.open(io.BytesIO(data))
    picture.load()
    assert picture.size == (800, 600) and data.endswith(b"IEND\xaeB`\x82")


def test_a_checkpoint_whose_domain_is_no_name_is_refused_in_one_line(tmp_path):
    """A list there raised "TypeError: unhashable type: 'list'" where the message names the command."""
    import zipfile

    make_image(tmp_path / "in.png")
    assert invoke(["torus", "in.png", *FAST, "-o", "a.csv", "--checkpoint", "c.npz"], tmp_path).exit_code == 0
    with zipfile.ZipFile(tmp_path / "c.npz") as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    metadata = json.loads(str(np.load(io.BytesIO(members["metadata.npy"]))[()]))
    metadata["settings"] = {key: [value] for key, value in metadata["settings"].items()}
    buffer = io.BytesIO()
    np.save(buffer, np.array(json.dumps(metadata)))
    with zipfile.ZipFile(tmp_path / "c.npz", "w") as archive:
        for name, data in {**members, "metadata.npy": buffer.getvalue()}.items():
            archive.writestr(name, data)
    args = ["torus", "in.png", *FAST, "-o", "a.csv", "--checkpoint", "c.npz", "--resume"]
    refused(args, tmp_path, "corrupt checkpoint metadata (its domain is not a name)")


def test_resuming_a_line_with_another_length_names_the_length(tmp_path):
    """It said 'the image or -M differs (points was 900, now 600)': a line's points are its nodes."""
    make_image(tmp_path / "in.png", (40, 30))
    base = ["line", "in.png", "-M", 60, "--iterations", 2, "-q", "-o", "a.csv", "--checkpoint", "c.npz"]
    assert invoke([*base, "--length", 600], tmp_path).exit_code == 0
    result = invoke([*base, "--length", 300, "--resume"], tmp_path)
    assert result.exit_code == 1 and "Traceback" not in result.output
    # Not "points was 240, now 120", which read as -M (a fifth sweep): the length the user gave.
    assert "the image or --length differs (length was 600.0, now 300.0; " in result.stderr


def test_hidden_files_in_a_folder_of_frames_are_not_frames(tmp_path):
    """A macOS '._0.png' (no image) was read as a frame and stopped the run; the glob already left it out."""
    for name in ("0.png", "1.png"):
        make_image(tmp_path / name)
    (tmp_path / "._0.png").write_bytes(b"\x00\x05\x16\x07 AppleDouble")
    (tmp_path / ".hidden.png").write_bytes(b"junk")
    (tmp_path / "2.png").mkdir()  # a folder is no frame either
    frames = open_frames(str(tmp_path))
    assert [name.rsplit("/", 1)[-1] for name in frames.files] == ["0.png", "1.png"]


def test_a_globe_png_counts_its_float_planes_before_the_run(tmp_path, monkeypatch):
    """A gray globe 8192 pixels wide peaked at 16.9 GB where its check counted 2 bytes a pixel (2.4 GB): on a
    machine with less memory it would have been killed after its run. The map's picture is drawn on 8 bits."""
    canvas_pixels = (4 * 1024) ** 2  # --png-width 1024, supersampled 4 times
    between = canvas_pixels * 1.1 * (2 + float_picture_layers(1)) / 2
    monkeypatch.setattr(stipple.allocator, "available_memory", lambda: between)
    args = ["sphere", "--uniform", "-M", 30, "--iterations", 2, "-q", "--png-width", 1024]
    refused([*args, "-o", "g.png"], tmp_path, "of memory to draw")
    assert invoke([*args, "--projection", "equirect", "--png-width", 512, "-o", "m.png"], tmp_path).exit_code == 0


def test_a_run_whose_messages_nobody_reads_still_writes_its_outputs(tmp_path):
    """``stipple torus ... 2>&1 | head -1``: the run stopped at its next message (BrokenPipeError), exit 1, no
    output written, where the outputs are its result; now the messages go quiet and the run finishes."""
    import subprocess
    import sys

    make_image(tmp_path / "in.png")
    process = subprocess.Popen(
        [sys.executable, "-m", "stipple", "torus", "in.png", "-M", "30", "-N", "8", "--iterations", "2", "-v"]
        + ["-o", "a.csv"],
        cwd=tmp_path,
        stderr=subprocess.PIPE,
    )
    process.stderr.close()  # the reader goes away before the first message
    assert process.wait(timeout=120) == 0
    assert (tmp_path / "a.csv").read_text().startswith("x,y\n")
