"""Image and map loading: formats, bit depths, alpha, orientation, density conventions."""

import io
import re

import numpy as np
import pytest
from PIL import Image

from stipple.errors import StippleError
from stipple.io.images import load_density


def saved(image, fmt, **kwargs):
    buffer = io.BytesIO()
    image.save(buffer, format=fmt, **kwargs)
    buffer.seek(0)
    buffer.name = f"test.{fmt.lower()}"
    return buffer


GRAY = np.array([[0, 64], [128, 255]], dtype=np.uint8)


@pytest.mark.parametrize("fmt", ["PNG", "TIFF", "BMP"])
def test_lossless_8bit_gray(fmt):
    density = load_density(saved(Image.fromarray(GRAY), fmt))
    np.testing.assert_allclose(density, 1 - GRAY / 255)


def test_jpeg_is_close():
    picture = np.repeat(np.repeat(GRAY, 8, axis=0), 8, axis=1)
    density = load_density(saved(Image.fromarray(picture), "JPEG", quality=95))
    np.testing.assert_allclose(density, 1 - picture / 255, atol=0.03)


def test_16bit_png_keeps_precision():
    values = np.array([[0, 1000], [40000, 65535]], dtype=np.uint16)
    density = load_density(saved(Image.fromarray(values), "PNG"))
    np.testing.assert_allclose(density, 1 - values / 65535, atol=1e-12)


def test_rgb_uses_luma():
    rgb = np.zeros((2, 2, 3), dtype=np.uint8)
    rgb[0, 0] = [255, 0, 0]
    rgb[0, 1] = [0, 255, 0]
    rgb[1, 0] = [0, 0, 255]
    rgb[1, 1] = [255, 255, 255]
    density = load_density(saved(Image.fromarray(rgb), "PNG"))
    np.testing.assert_allclose(density, 1 - np.array([[0.299, 0.587], [0.114, 1.0]]), atol=1e-12)


def test_transparent_pixels_are_white_paper():
    rgba = np.zeros((2, 2, 4), dtype=np.uint8)
    rgba[..., 3] = [[0, 255], [128, 255]]
    density = load_density(saved(Image.fromarray(rgba), "PNG"))
    np.testing.assert_allclose(density, [[0, 1], [128 / 255, 1]], atol=1e-12)


def test_palette_and_bilevel_images():
    palette = Image.fromarray(GRAY).convert("P")
    np.testing.assert_allclose(load_density(saved(palette, "PNG")), 1 - GRAY / 255, atol=1e-12)
    bilevel = Image.fromarray(GRAY).convert("1")
    assert set(np.unique(load_density(saved(bilevel, "PNG")))) <= {0.0, 1.0}


def test_exif_orientation_is_applied():
    picture = np.zeros((2, 3), dtype=np.uint8)
    picture[0, 0] = 255
    image = Image.fromarray(picture)
    exif = Image.Exif()
    exif[0x0112] = 6  # rotate 90° clockwise for display
    density = load_density(saved(image, "JPEG", exif=exif.tobytes(), quality=100))
    assert density.shape == (3, 2)


def test_rectangular_aspect_is_kept():
    density = load_density(saved(Image.new("L", (40, 10), 0), "PNG"))
    assert density.shape == (10, 40)


def test_invert_and_gamma():
    source = saved(Image.fromarray(GRAY), "PNG")
    inverted = load_density(source, invert=True, gamma=2.0)
    np.testing.assert_allclose(inverted, (GRAY / 255) ** 2)


def test_npy_maps_rescale_linearly_with_an_override_range():
    values = np.array([[-100.0, 0.0], [50.0, 100.0]])
    buffer = io.BytesIO()
    np.save(buffer, values)
    data = buffer.getvalue()
    np.testing.assert_allclose(load_density(io.BytesIO(data)), [[0, 0.5], [0.75, 1]])
    np.testing.assert_allclose(load_density(io.BytesIO(data), value_range=(0, 50)), [[0, 0], [1, 1]])


def test_range_and_levels_are_refused_where_they_would_be_ignored(tmp_path):
    """--range on an image and --levels on a .npy map were accepted and changed nothing."""
    from PIL import Image

    from stipple.errors import StippleError
    from stipple.io.images import load_density

    Image.fromarray(np.full((8, 8), 100, np.uint8)).save(tmp_path / "g.png")
    np.save(tmp_path / "m.npy", np.arange(64.0).reshape(8, 8))
    with pytest.raises(StippleError, match="--range is for .npy maps"):
        load_density(tmp_path / "g.png", value_range=(0.0, 1.0))
    with pytest.raises(StippleError, match="--levels is for images"):
        load_density(tmp_path / "m.npy", levels="auto")
    # A map that --range leaves at zero was called "the image is blank (all white)".
    with pytest.raises(StippleError, match="no density is left under --range 100 200: every value is at or below 100"):
        load_density(tmp_path / "m.npy", value_range=(100.0, 200.0))
    assert np.all(load_density(tmp_path / "m.npy", value_range=(100.0, 200.0), invert=True) == 1.0)
    with pytest.raises(StippleError, match="blank under --invert"):
        load_density(tmp_path / "m.npy", value_range=(-10.0, -5.0), invert=True)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"value_range": 5}, "range must be two numbers LO HI, not 5"),
        ({"value_range": (1, 2, 3)}, "range must be two numbers LO HI"),
        ({"value_range": ("a", "b")}, "range must be two numbers LO HI"),
        ({"levels": (0.1, 0.5, 0.9)}, "levels must be two numbers BLACK,WHITE"),
        ({"levels": "bogus"}, "levels must be 'auto' or BLACK,WHITE"),
        ({"gamma": "2"}, "gamma must be a positive number"),
    ],
)
def test_load_density_names_a_setting_of_the_wrong_shape_or_type(tmp_path, options, message):
    """Each failed in Python's words (unpacking, float(), a comparison of str and int; a hostile review)."""
    path = tmp_path / ("map.npy" if "value_range" in options else "gray.png")
    if "value_range" in options:
        np.save(path, np.arange(12.0).reshape(3, 4))
    else:
        Image.fromarray(np.arange(12, dtype=np.uint8).reshape(3, 4) * 20).save(path)
    with pytest.raises(StippleError, match=re.escape(message)):
        load_density(path, **options)
