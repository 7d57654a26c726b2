"""Messages say what is wrong: no 'map is constant' for a reversed range, no 'pickled data' for a PNG."""

import io

import numpy as np
import pytest
from PIL import Image
from safety_helpers import FAST, invoke, make_image, refused

from stipple import load_density


@pytest.fixture
def folder(tmp_path):
    make_image(tmp_path / "in.png")
    np.save(tmp_path / "map.npy", np.arange(20.0).reshape(4, 5))
    (tmp_path / "out.csv").write_text("previous output\n")
    return tmp_path


def run_torus(folder, source, *extra):
    return ["torus", source, *FAST, "-o", "out.csv", *extra]


def test_reversed_range_names_the_range(folder):
    refused(run_torus(folder, "map.npy", "--range", "1", "0"), folder, "range must be two finite numbers LO HI")
    result = invoke(run_torus(folder, "map.npy", "--range", "1", "0"), folder)
    assert "constant" not in result.stderr


def test_long_npy_header_is_not_called_objects(folder):
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), }" + " " * 20000 + "\n"
    data = b"\x93NUMPY\x02\x00" + len(header).to_bytes(4, "little") + header.encode() + b"\0" * 32
    (folder / "long.npy").write_bytes(data)
    refused(run_torus(folder, "long.npy"), folder, ".npy header is 20060 bytes long; at most 10000 are read")


def test_objects_are_still_called_objects(folder):
    np.save(folder / "objects.npy", np.array([{"a": 1}, None], dtype=object), allow_pickle=True)
    refused(run_torus(folder, "objects.npy"), folder, "holds Python objects")


def test_png_as_checkpoint_is_not_a_checkpoint(folder):
    refused(run_torus(folder, "in.png", "--checkpoint", "other.png", "--resume"), folder, "no checkpoint to resume")
    make_image(folder / "other.png")
    result = invoke(run_torus(folder, "in.png", "--checkpoint", "other.png", "--resume"), folder)
    assert "not a stipple checkpoint (not a .npz archive)" in result.stderr and "pickle" not in result.stderr


def test_usage_errors_are_one_line(folder):
    refused(run_torus(folder, "in.png", "--png-width", "5"), folder, "'--png-width'", code=2)
    refused(run_torus(folder, "in.png", "--no-such-option"), folder, "No such option", code=2)


def test_byte_order_mark_in_csv_is_skipped(folder):
    plain = "x,y\n1.5,2.5\n3.5,7.5\n"
    (folder / "plain.csv").write_text(plain)
    (folder / "bom.csv").write_bytes(b"\xef\xbb\xbf" + plain.encode())
    assert invoke(["render", "plain.csv", "-o", "a.svg"], folder).exit_code == 0
    assert invoke(["render", "bom.csv", "-o", "b.svg"], folder).exit_code == 0
    assert (folder / "a.svg").read_bytes() == (folder / "b.svg").read_bytes()


def test_non_utf8_csv_says_so(folder):
    (folder / "latin.csv").write_bytes("x,y\n1,2\n# caf\xe9\n".encode("latin-1"))
    refused(["render", "latin.csv", "-o", "a.svg"], folder, "not UTF-8 text")


def tiff_bytes(values):
    buffer = io.BytesIO()
    Image.fromarray(values.astype(np.float32), mode="F").save(buffer, format="TIFF")
    buffer.seek(0)
    return buffer


@pytest.mark.parametrize("scale", [1.0, 255.0, 65535.0])
def test_float_tiffs_are_rescaled_like_integer_images(scale):
    levels = np.array([[0.0, 0.25, 0.5], [0.75, 1.0, 0.5]])
    assert np.allclose(load_density(tiff_bytes(levels * scale)), 1 - levels, atol=1e-6)


@pytest.mark.parametrize(
    "values,shown",
    [
        ([[-1.0, 0.5], [0.2, 0.1]], "[-1, 0.5]"),
        ([[1e6, 0], [0, 1]], "1e+06"),
        ([[-5.0, -5.0], [-5.0, -5.0]], "not [-5, -5]"),  # "[-5, 0]": a range the image does not have
    ],
)
def test_float_tiffs_out_of_range_are_refused(folder, values, shown):
    (folder / "f.tiff").write_bytes(tiff_bytes(np.array(values)).getvalue())
    refused(run_torus(folder, "f.tiff"), folder, "float image values must lie in [0, 1], [0, 255] or [0, 65535]")
    assert shown in invoke(run_torus(folder, "f.tiff"), folder).stderr


@pytest.mark.parametrize(
    "args, starts",
    [
        (["torus", "in.png", *FAST, "-o", "new.csv", "--init", "stratifed"], "stratified, density, uniform"),
        (["sphere", "map.npy", "-M", "30", "-N", "4", "-o", "new.csv", "--init", "lattice"], "stratified, density"),
        (["design", "-t", "4", "-o", "new.csv", "--init", "fibonacci"], "auto, lattice, uniform"),
    ],
    ids=["torus", "sphere", "design"],
)
def test_a_mistyped_start_names_the_starts_and_the_file(folder, args, starts):
    # It said only "cannot read stratifed: No such file or directory".
    refused(args, folder, f"--init: {args[-1]!r} is neither a start ({starts}")


def test_an_output_that_is_a_folder_is_called_one(folder):
    # It said "unknown output format (none)".
    (folder / "results").mkdir()
    refused(["torus", "in.png", *FAST, "-o", "results"], folder, "results: is a directory; name a file in it")


def test_a_builtin_density_for_image_points_is_called_the_spheres(folder):
    (folder / "p.csv").write_text("x,y\n1.5,2.5\n3.5,7.5\n9.5,4.5\n")
    refused(["evaluate", "p.csv", "builtin:gaussians"], folder, "the built-in densities are the sphere's")
