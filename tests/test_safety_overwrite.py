"""Outputs, checkpoints and reports that name an input (or each other) are refused before any work."""

import os

import numpy as np
import pytest
from safety_helpers import FAST, make_image, refused


@pytest.fixture
def folder(tmp_path):
    make_image(tmp_path / "in.png")
    rows = "\n".join(f"{x + 0.5},{(x * 7) % 12 + 0.5}" for x in range(30))
    (tmp_path / "g.csv").write_text("x,y\n" + rows + "\n")
    (tmp_path / "p.csv").write_text("x,y\n1.5,2.5\n3.5,7.5\n9.5,4.5\n")
    (tmp_path / "s.csv").write_text("lon,lat\n" + "\n".join(f"{10 * i},{i - 15}" for i in range(30)) + "\n")
    np.save(tmp_path / "map.npy", np.arange(32.0).reshape(4, 8))
    (tmp_path / "old.svg").write_text("<svg>keep me</svg>\n")
    os.symlink("in.png", tmp_path / "link.png")
    os.symlink("p.csv", tmp_path / "link.csv")
    os.link(tmp_path / "g.csv", tmp_path / "hard.csv")
    (tmp_path / "sub").mkdir()
    return tmp_path


CASES = {
    "image as output": (["torus", "in.png", *FAST, "-o", "in.png"], "would overwrite the image"),
    "image by another spelling": (["torus", "in.png", *FAST, "-o", "sub/../in.png"], "would overwrite the image"),
    "symlink to the image": (["torus", "in.png", *FAST, "-o", "link.png"], "would overwrite the image"),
    "image through a symlink input": (["torus", "link.png", *FAST, "-o", "in.png"], "would overwrite the image"),
    "init CSV as output": (["torus", "in.png", *FAST, "--init", "g.csv", "-o", "g.csv"], "--init file"),
    "hard link to the init CSV": (["torus", "in.png", *FAST, "--init", "g.csv", "-o", "hard.csv"], "--init file"),
    "sphere init as output": (
        ["sphere", "map.npy", "-M", "30", "-N", "4", "-q", "--init", "s.csv", "-o", "s.csv"],
        "--init file",
    ),
    "checkpoint is an output": (["torus", "in.png", *FAST, "--checkpoint", "c.csv", "-o", "c.csv"], "as checkpoint"),
    "checkpoint is the image": (["torus", "in.png", *FAST, "--checkpoint", "in.png"], "checkpoint would overwrite"),
    "checkpoint is the map": (["sphere", "map.npy", "-M", "30", "-N", "4", "--checkpoint", "map.npy"], "the map"),
    "two outputs are one file": (["torus", "in.png", *FAST, "-o", "a.csv", "-o", "./a.csv"], "its own file"),
    "render onto its points": (["render", "p.csv", "-o", "p.csv"], "would overwrite the points"),
    "render onto a symlink of its points": (["render", "p.csv", "-o", "link.csv"], "would overwrite the points"),
    "render onto --like": (["render", "p.csv", "--like", "in.png", "-o", "in.png"], "--like image"),
    "evaluate --json onto the points": (["evaluate", "p.csv", "in.png", "--json", "p.csv"], "must end in .json"),
    "evaluate --spectrum onto the image": (["evaluate", "p.csv", "in.png", "--spectrum", "in.png"], "the input"),
    "evaluate --json and --spectrum on one file": (
        ["evaluate", "p.csv", "in.png", "--json", "r.json", "--spectrum", "r.json"],
        "must end in .png",
    ),
}


@pytest.mark.parametrize("args,message", CASES.values(), ids=CASES.keys())
def test_outputs_never_replace_inputs(folder, args, message):
    refused(args, folder, message)


def test_config_file_is_an_input(folder):
    (folder / "settings.csv").write_text("points = 30\nbandwidth = 8\n")
    refused(["torus", "in.png", "--config", "settings.csv", "-q", "-o", "settings.csv"], folder, "the config")


def test_evaluate_json_through_a_symlink_to_the_points(folder):
    os.symlink("p.csv", folder / "report.json")
    refused(["evaluate", "p.csv", "in.png", "--json", "report.json"], folder, "would overwrite the points")


def test_distinct_outputs_still_work(folder):
    from safety_helpers import invoke

    result = invoke(["torus", "in.png", *FAST, "--init", "g.csv", "-o", "new.csv", "-o", "old.svg"], folder)
    assert result.exit_code == 0, result.output
    assert (folder / "new.csv").read_text().startswith("x,y\n")
    assert (folder / "old.svg").read_text() != "<svg>keep me</svg>\n"


def test_read_only_outputs_are_not_replaced(folder):
    (folder / "old.svg").chmod(0o444)
    refused(["torus", "in.png", *FAST, "-o", "old.svg"], folder, "old.svg: is read-only")


def test_batch_makes_no_folder_in_a_read_only_one(folder):
    # As torus -o refuses a file there, even for root, who could write into it (a hostile sweep).
    (folder / "sub").chmod(0o555)
    try:
        refused(["batch", "in.png", *FAST, "-d", "sub/new/out"], folder, "(the folder " + str(folder / "sub"))
        assert not (folder / "sub" / "new").exists()
    finally:
        (folder / "sub").chmod(0o755)


@pytest.mark.parametrize("source", ["frames", "frames/*.png"])
@pytest.mark.parametrize("output", ["d.csv", "out.mp4"])
def test_a_video_output_linked_to_a_frame_image_is_refused(folder, source, output):
    """An output linked to one of a folder's (or glob's) frame images was written into it: only SOURCE itself
    was compared with the outputs (a hostile review)."""
    if output.endswith(".mp4"):
        pytest.importorskip("av", reason="an MP4 output needs PyAV (pip install 'stipple[video]')")
    (folder / "frames").mkdir()
    for index in range(3):
        make_image(folder / "frames" / f"{index}.png")
    os.symlink("frames/1.png", folder / output)
    refused(["video", source, "-M", "20", "-q", "-o", output], folder, "would overwrite the input frame")
