"""One image reader for every command (issue 33, row 1): the same picture stored as 8-bit, 16-bit, float TIFF,
palette PNG and RGBA has the same tone on the gray and the colour paths of every command that reads images."""

import json

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main
from stipple.io.images import image_colour, image_density, load_colour, load_density

# A left-dark ramp of 8-bit gray values (every storage below holds exactly these tones).
GRAY = np.tile(np.linspace(20, 235, 24).round().astype(np.uint8), (16, 1))
STORAGES = ("8bit.png", "16bit.png", "float.tiff", "palette.png", "rgba.png")
FAST = ["-M", "60", "-N", "12", "--iterations", "3", "-q", "--seed", "3"]


def store(folder, storage):
    """The ramp written in one storage; returns its path."""
    path = folder / storage
    if storage == "8bit.png":
        Image.fromarray(GRAY).save(path)
    elif storage == "16bit.png":
        Image.fromarray(GRAY.astype(np.uint16) * 257).save(path)
        assert Image.open(path).mode.startswith("I;16")
    elif storage == "float.tiff":
        Image.fromarray((GRAY / 255.0).astype(np.float32)).save(path)
        assert Image.open(path).mode == "F"
    elif storage == "palette.png":
        indexed = Image.new("P", GRAY.shape[::-1])
        indexed.putpalette([value for level in range(256) for value in (level, level, level)])
        indexed.putdata(list(GRAY.ravel()))
        indexed.save(path)
        assert Image.open(path).mode == "P"
    else:
        rgba = np.dstack([GRAY, GRAY, GRAY, np.full_like(GRAY, 255)])
        Image.fromarray(rgba, mode="RGBA").save(path)
    return path


@pytest.mark.parametrize("storage", STORAGES)
def test_gray_and_colour_readers_give_the_8bit_tones(tmp_path, storage):
    path = store(tmp_path, storage)
    expected = GRAY / 255.0
    gray = 1.0 - load_density(path)
    colour = load_colour(path)
    np.testing.assert_allclose(gray, expected, atol=1e-6)
    for channel in range(3):
        np.testing.assert_allclose(colour[..., channel], expected, atol=1e-6)
    decoded = Image.open(path)  # the video frames' path: decoded pictures
    np.testing.assert_allclose(image_colour(decoded), colour, atol=1e-12)
    np.testing.assert_allclose(1.0 - image_density(decoded), gray, atol=1e-12)


def mean_x(csv_text):
    rows = [line.split(",") for line in csv_text.strip().splitlines()[1:]]
    values = [float(row[1] if row[0].isdigit() and len(row) > 3 else row[0]) for row in rows]
    return np.mean(values), len(values)


def run(args):
    result = CliRunner().invoke(main, [str(arg) for arg in args])
    assert result.exit_code == 0, result.output
    assert "Traceback" not in result.output
    return result


def command_result(command, image, folder):
    """What ``command`` makes of ``image``: numbers that depend on its tones only."""
    out = folder / f"{command}.csv"
    if command == "torus":
        run(["torus", image, *FAST, "-o", out])
    elif command == "torus-palette":
        run(["torus", image, *FAST, "--palette", "cmyk", "-o", out])
    elif command == "colour":
        run(["colour", image, *FAST, "--palette", "#ff0000,#00ffff,black", "-o", out])
    elif command == "line":
        run(["line", image, *FAST, "--length", "8", "-o", out])
    elif command == "batch":
        run(["batch", image, *FAST, "--format", "csv", "-d", folder / "batch"])
        out = folder / "batch" / (image.stem + ".csv")
    elif command == "video":
        frames = folder / "frames"
        frames.mkdir()
        for index in range(2):
            (frames / f"{index}{image.suffix}").write_bytes(image.read_bytes())
        run(["video", frames, *FAST, "-o", out])
    elif command == "evaluate":
        picture = folder / "drawn.png"
        Image.fromarray(np.where(GRAY > 128, 255, 0).astype(np.uint8)).save(picture)
        report = {}
        for gray in (True, False):
            result = run(["evaluate", picture, image, "--json", "-", "--gray" if gray else "--colour"])
            report[gray] = json.loads(result.stdout[result.stdout.index("{") :])
        return report
    return mean_x(out.read_text())


COMMANDS = ("torus", "torus-palette", "colour", "line", "batch", "video", "evaluate")


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("storage", STORAGES[1:])
def test_every_command_draws_every_storage_as_the_8bit_picture(tmp_path, command, storage):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    reference = command_result(command, store(tmp_path / "a", "8bit.png"), tmp_path / "a")
    stored = command_result(command, store(tmp_path / "b", storage), tmp_path / "b")
    np.testing.assert_allclose(numbers(stored), numbers(reference), rtol=1e-3, atol=1e-6)


def numbers(value):
    """Every number of a result (a report's nested dictionaries and lists, or a tuple), in a fixed order."""
    if isinstance(value, dict):
        return [number for key in sorted(value, key=str) for number in numbers(value[key])]
    if isinstance(value, (list, tuple)):
        return [number for item in value for number in numbers(item)]
    return [float(value)] if isinstance(value, (int, float, np.number)) else []


@pytest.mark.parametrize("mode", ["RGBA", "RGB", "LA", "P", "CMYK"])
def test_colour_images_gray_is_the_exact_luma_composited_on_white(tmp_path, mode, rng):
    """The gray of a colour image, in 32-bit integers a channel at a time, against the exact rational
    ``(luma alpha + 255000 (255 - alpha)) / (255000 * 255)`` computed in 64-bit integers."""
    from stipple.io.images import LUMA_PER_MILLE, load_gray

    pixels = rng.integers(0, 256, (37, 53, 4), dtype=np.uint8)
    pixels[0, :4] = [[255, 255, 255, 255], [0, 0, 0, 255], [0, 0, 0, 0], [255, 255, 255, 0]]
    image = Image.fromarray(pixels, "RGBA")
    image = image if mode == "RGBA" else image.convert(mode)
    path = tmp_path / ("image.tiff" if mode == "CMYK" else "image.png")
    image.save(path)
    rgba = np.asarray(Image.open(path).convert("RGBA"), dtype=np.int64)
    luma, alpha = rgba[..., :3] @ LUMA_PER_MILLE, rgba[..., 3]
    exact = (luma * alpha + 255000 * (255 - alpha)) / (255000.0 * 255.0)
    assert np.array_equal(load_gray(path.read_bytes()), exact)
    assert exact.min() >= 0 and exact.max() <= 1


@pytest.mark.parametrize("mode", ["RGBA", "RGB", "P", "CMYK"])
def test_colour_images_are_composited_on_white_opaque_or_not(mode, rng):
    """``image_colour`` skips the composite where every pixel is opaque: the same values as composited."""
    from stipple.io.images import image_colour

    pixels = rng.integers(0, 256, (29, 41, 4), dtype=np.uint8)
    image = Image.fromarray(pixels, "RGBA")
    image = image if mode == "RGBA" else image.convert(mode)
    rgba = np.asarray(image.convert("RGBA"), dtype=np.float64) / 255.0
    composited = rgba[..., :3] * rgba[..., 3:] + (1.0 - rgba[..., 3:])
    assert np.array_equal(image_colour(image), composited)
    if mode in ("RGBA", "RGB"):  # both paths taken
        assert (mode == "RGBA") == bool(np.any(rgba[..., 3] < 1))
