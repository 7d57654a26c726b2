"""Garbage that used to be accepted silently is refused, naming the parameter and the allowed range."""

import numpy as np
import pytest
from PIL import Image
from safety_helpers import FAST, invoke, make_image, refused

from stipple import load_density

WHITE = {
    "RGB": Image.new("RGB", (8, 6), (255, 255, 255)),
    "RGBA half-transparent white": Image.new("RGBA", (8, 6), (255, 255, 255, 128)),
    "RGBA transparent black": Image.new("RGBA", (8, 6), (0, 0, 0, 0)),
    "LA": Image.new("LA", (8, 6), (255, 77)),
    "palette": Image.new("P", (8, 6), 3),
}


@pytest.fixture
def folder(tmp_path):
    make_image(tmp_path / "in.png")
    (tmp_path / "out.csv").write_text("previous output\n")
    return tmp_path


def save_white(folder, name):
    image = WHITE[name]
    if image.mode == "P":
        image.putpalette([255, 255, 255] * 256)
    image.save(folder / "white.png")
    return folder / "white.png"


@pytest.mark.parametrize("name", WHITE)
def test_all_white_images_are_exactly_blank(folder, name):
    assert np.all(load_density(save_white(folder, name)) == 0)
    refused(["torus", "white.png", *FAST, "-o", "out.csv"], folder, "blank (all white)")
    refused(["sphere", "white.png", "-M", "30", "-N", "4", "-q", "-o", "out.csv"], folder, "zero everywhere")


def test_gray_rgb_keeps_its_tone():
    image = Image.new("RGB", (4, 4), (128, 128, 128))
    assert np.allclose(load_density_of(image), 1 - 128 / 255, rtol=0, atol=1e-15)


def load_density_of(image):
    import io

    buffer = io.BytesIO()
    image.save(buffer, format="PNG")
    buffer.seek(0)
    return load_density(buffer)


NUMBERS = {
    "--width 1e309mm": (["--width", "1e309mm", "-o", "x.svg"], "width must be a length (mm"),
    "--width 1e-9mm": (["--width", "1e-9mm", "-o", "x.svg"], "from 0.001mm to 1e+06mm"),
    "--dot-radius 1e309": (["--dot-radius", "1e309", "-o", "x.svg"], "dot-radius must be a length (mm"),
    "--dot-radius 2e6mm": (["--dot-radius", "2e6mm", "-o", "x.svg"], "from 0.001mm to 1e+06mm"),
    "--epsilon 0": (["--epsilon", "0"], "epsilon must be a number in [1e-14, 1e-2], not 0.0"),
    "--range nan 1": (["--range", "nan", "1"], "range must be two finite numbers LO HI with LO < HI"),
    "--gamma inf": (["--gamma", "inf"], "gamma must be a positive number"),
    "--tol nan": (["--tol", "nan"], "tol must be a positive number"),
}


@pytest.mark.parametrize("extra,message", NUMBERS.values(), ids=NUMBERS.keys())
def test_out_of_range_numbers(folder, extra, message):
    refused(["torus", "in.png", *FAST, "-o", "out.csv", *extra], folder, message)


def test_integer_options_refuse_fractions_in_a_config(folder):
    (folder / "c.toml").write_text("threads = 3.7\n")
    refused(["torus", "in.png", "--config", "c.toml", "-o", "out.csv"], folder, "key 'threads'", code=2)


POINTS = {
    "zero vector": ("x,y,z\n0,0,0\n1,0,0\n", "point 1 is the zero vector"),
    "latitude 95": ("lon,lat\n10,95\n0,0\n", "latitudes must lie in [-90, 90] degrees"),
    "NaN coordinate": ("x,y\nnan,1\n2,3\n", "NaN or infinite"),
    "no rows": ("x,y\n", "no points"),
}


@pytest.mark.parametrize("text,message", POINTS.values(), ids=POINTS.keys())
def test_bad_point_sets_in_render(folder, text, message):
    (folder / "p.csv").write_text(text)
    refused(["render", "p.csv", "-o", "out.csv"], folder, message)


def test_tiny_and_huge_direction_vectors_are_normalised(folder):
    (folder / "p.csv").write_text("x,y,z\n1e-200,0,0\n0,1e300,1e300\n")
    assert invoke(["render", "p.csv", "--coords", "xyz", "-o", "q.csv"], folder).exit_code == 0
    written = np.loadtxt(folder / "q.csv", delimiter=",", skiprows=1)
    assert np.allclose(written, [[1, 0, 0], [0, 2**-0.5, 2**-0.5]])


@pytest.mark.parametrize("iteration", [-5, 10**12])
def test_checkpoint_iteration_out_of_range(folder, iteration):
    assert invoke(["torus", "in.png", *FAST, "--checkpoint", "c.npz", "-o", "a.csv"], folder).exit_code == 0
    with np.load(folder / "c.npz") as archive:
        contents = dict(archive)
    contents["iteration"] = np.asarray(iteration)
    np.savez(folder / "c.npz", **contents)
    args = ["torus", "in.png", *FAST[:4], "--iterations", "5", "-q", "--checkpoint", "c.npz", "--resume"]
    refused([*args, "-o", "out.csv"], folder, f"iteration {iteration} is outside [0, 1000000000]")


def test_npy_with_a_negative_size_in_its_shape(folder):
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (-1, 4), }"
    header += " " * (63 - (10 + len(header)) % 64) + "\n"
    data = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + b"\0" * 64
    (folder / "neg.npy").write_bytes(data)
    refused(["torus", "neg.npy", *FAST, "-o", "out.csv"], folder, "negative size in shape (-1, 4)")


def test_integer_images_out_of_range(folder):
    values = np.array([[-5, 100000], [3, 4]], dtype=np.int32)
    Image.fromarray(values, mode="I").save(folder / "i32.tiff")
    refused(
        ["torus", "i32.tiff", *FAST, "-o", "out.csv"], folder, "must lie in [0, 255] or [0, 65535], not [-5, 100000]"
    )
