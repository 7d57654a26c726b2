"""Reading images and numeric maps into densities ``w >= 0`` (dark = many dots), and colour images into RGB."""

import io
import math
import re
import tokenize
import warnings

import numpy as np
from PIL import Image, ImageOps, UnidentifiedImageError

from ..checks import is_real, two_numbers
from ..errors import StippleError
from .levels import check_levels, stretch_levels
from .sources import read_source, source_or_stdin

NPY_MAGIC = b"\x93NUMPY"
MAX_NPY_HEADER = 10_000
# Rec. 601 luma in thousandths: integer sums keep white exactly white (0.299 + 0.587 + 0.114 != 1 in floats).
LUMA_PER_MILLE = np.array([299, 587, 114])
# The same weights for colours in [0, 1]: the luminance of Rec. 601 everywhere (separation, tone, measures).
LUMA = LUMA_PER_MILLE / 1000
_FLOAT_SCALES = (1.0, 255.0, 65535.0)


def load_gray(data, name="input"):
    """Gray values ``u`` in [0, 1] (0 = black) of an image file's bytes; alpha is composited on white.

    PNG, JPEG, TIFF and anything else Pillow opens; 8- and 16-bit gray, RGB(A), palettes, 32-bit float
    (values in [0, 1], or 0..255 / 0..65535, which are rescaled like 8- and 16-bit images). EXIF
    orientation is applied. Pillow's decompression-bomb guard stays on.
    """
    return _gray_values(open_image(data, name, "not a supported image or .npy file, or truncated"), name)


def open_image(data, name, unknown):
    """A decoded image (EXIF orientation applied) from a file's bytes, Pillow's decompression-bomb guard on;
    ``unknown`` says what an undecodable file may be."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            image = Image.open(io.BytesIO(data))
            image.load()
    except (Image.DecompressionBombError, Image.DecompressionBombWarning):
        raise StippleError(f"{name}: image is too large (Pillow's decompression-bomb guard)") from None
    except UnidentifiedImageError:
        raise StippleError(f"{name}: cannot decode image ({unknown})") from None
    except (OSError, SyntaxError, ValueError, MemoryError) as error:
        raise StippleError(f"{name}: cannot decode image ({error or type(error).__name__})") from None
    return ImageOps.exif_transpose(image)


def _gray_values(image, name):
    if image.mode in ("I;16", "I;16B", "I;16L", "I;16N"):
        return np.asarray(image, dtype=np.float64) / 65535.0
    if image.mode == "I":
        values = np.asarray(image, dtype=np.float64)
        if values.min(initial=0) < 0 or values.max(initial=0) > 65535:
            raise StippleError(
                f"{name}: 32-bit integer image values must lie in [0, 255] or [0, 65535], "
                f"not [{values.min():g}, {values.max():g}]"
            )
        return values / (65535.0 if values.max(initial=0) > 255 else 255.0)
    if image.mode == "F":
        return _float_gray(np.asarray(image, dtype=np.float64), name)
    if image.mode in ("L", "1"):
        return np.asarray(image.convert("L"), dtype=np.float64) / 255.0
    rgba = np.asarray(image.convert("RGBA"))
    # 32-bit integers, a channel at a time: a 12-megapixel photo in 0.2 s (2.4 s as one 64-bit product).
    alpha = rgba[..., 3].astype(np.int32)
    luma = sum(rgba[..., channel].astype(np.int32) * int(LUMA_PER_MILLE[channel]) for channel in range(3))
    # (luma * alpha + 255000 * (255 - alpha)) / (255000 * 255) in exact integers (at most 255000 * 255 < 2^31):
    # white stays 1.0.
    return (luma * alpha + 255000 * (255 - alpha)) / (255000.0 * 255.0)


def _float_gray(values, name):
    """A float image's values in [0, 1]; images stored as 0..255 or 0..65535 are rescaled like integer ones."""
    if not np.all(np.isfinite(values)):
        raise StippleError(f"{name}: image contains NaN or infinite values")
    # The values' own range in the message: a float image of -5 everywhere was "not [-5, 0]".
    low, high = (values.min(), values.max()) if values.size else (0.0, 0.0)
    scale = next((scale for scale in _FLOAT_SCALES if max(high, 0.0) <= scale), None)
    if low < 0 or scale is None:
        raise StippleError(
            f"{name}: float image values must lie in [0, 1], [0, 255] or [0, 65535], not [{low:g}, {high:g}]"
        )
    return values / scale


KIND_NAMES = {"biuf": "real numbers", "f": "floating-point numbers", "iu": "an integer", "U": "a text string"}


def load_array(data, name="input", kinds="biuf"):
    """An array from ``.npy`` bytes, checked before anything is allocated; nothing is unpickled.

    ``kinds`` are the accepted dtype kinds (default: real numbers, returned as float64). The header is
    parsed first (at most ``MAX_NPY_HEADER`` bytes); Python objects, other dtypes and headers that
    declare more data than the file holds are refused.
    """
    shape, fortran, dtype, offset = _npy_header(data, name)
    if dtype.hasobject:
        raise StippleError(f"{name}: .npy holds Python objects; only numeric arrays are read")
    if dtype.kind not in kinds or dtype.fields is not None or dtype.subdtype is not None:
        raise StippleError(f"{name}: .npy must hold {KIND_NAMES[kinds]}, not {dtype}")
    count = math.prod(shape)
    if count * dtype.itemsize > len(data) - offset:
        raise StippleError(
            f"{name}: truncated .npy file: its header declares shape {shape} ({count * dtype.itemsize} bytes) "
            f"but only {len(data) - offset} bytes follow"
        )
    array = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
    array = array.reshape(shape, order="F" if fortran else "C")
    return array.astype(np.float64) if kinds == "biuf" else array.copy()


def _npy_header(data, name):
    """``(shape, fortran_order, dtype, data_offset)`` of ``.npy`` bytes."""
    stream = io.BytesIO(data)
    try:
        major, _ = np.lib.format.read_magic(stream)
        length_bytes = 2 if major == 1 else 4
        length = int.from_bytes(stream.read(length_bytes), "little")
        if major not in (1, 2, 3):
            raise ValueError(f"unknown format version {major}")
        if length > MAX_NPY_HEADER:
            raise StippleError(f"{name}: .npy header is {length} bytes long; at most {MAX_NPY_HEADER} are read")
        stream.seek(-length_bytes, io.SEEK_CUR)
        reader = np.lib.format.read_array_header_1_0 if major == 1 else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = reader(stream, max_header_size=MAX_NPY_HEADER)
    # numpy parses the header with Python's tokenizer: an unclosed bracket raised its TokenError (a hostile sweep).
    except (ValueError, TypeError, SyntaxError, OverflowError, EOFError, UnicodeError, tokenize.TokenError) as error:
        if isinstance(error, StippleError):
            raise
        message = error.args[0] if isinstance(error, tokenize.TokenError) and error.args else error
        reason = " ".join(str(message).split())  # numpy's message quotes the header: a line of 6 KB for a deep one
        reason = re.sub(r"<ast\.(\w+) object at 0x[0-9a-fA-F]+>", r"a Python \1 expression", reason)  # not an address
        reason = reason if len(reason) <= 200 else reason[:197] + "..."
        raise StippleError(f"{name}: corrupt or truncated .npy file ({reason})") from None
    if any(size < 0 for size in shape):
        raise StippleError(f"{name}: corrupt .npy file (negative size in shape {shape})")
    return tuple(int(size) for size in shape), bool(fortran), dtype, stream.tell()


def check_grid(values, name="input"):
    """Raise unless ``values`` is a finite 2-D grid of at least 2×2 cells."""
    if values.ndim != 2:
        raise StippleError(f"{name}: expected a 2-D image or map, got shape {values.shape}")
    if min(values.shape) < 2:
        rows, columns = values.shape
        raise StippleError(f"{name}: must be at least 2×2 pixels (or map cells), got {columns}×{rows}")
    if not np.all(np.isfinite(values)):
        raise StippleError(f"{name}: map contains NaN or infinite values")
    return values


def check_range(value_range):
    """``(LO, HI)`` as floats if both are finite and ``LO < HI``."""
    low, high = two_numbers(value_range, "range", "LO HI")
    if not (np.isfinite(low) and np.isfinite(high) and low < high):
        raise StippleError(f"range must be two finite numbers LO HI with LO < HI, not {low:g} {high:g}")
    return low, high


def rescale(values, value_range=None, name="input"):
    """Linear map of ``value_range`` (default: the data's min and max) onto [0, 1], clipped."""
    if value_range is not None:
        low, high = check_range(value_range)
    else:
        low, high = values.min(), values.max()
        if not high > low:
            raise StippleError(
                f"{name}: map is constant ({low:g}); nothing to rescale (give --range LO HI, or --uniform on the "
                "sphere for a constant density)"
            )
    # Halving first keeps high - low finite for values near the float64 limits.
    span = high / 2 - low / 2
    if not span > 0:
        raise StippleError(f"{name}: the values span {high - low:g}, too little to rescale; give --range LO HI")
    # Values far outside a tiny span overflow to +-inf, which the clip sends to 0 or 1 (not a warning line).
    with np.errstate(over="ignore"):
        return np.clip((values / 2 - low / 2) / span, 0.0, 1.0)


def load_density(source, *, invert=False, gamma=1.0, value_range=None, levels=None, name=None, strict=True):
    """Density ``w`` on a grid (row 0 = top/north) from an image or a ``.npy`` map.

    Parameters
    ----------
    source : str or path or binary file
        Image (PNG, JPEG, TIFF, ...) or ``.npy`` numeric map.
    invert : bool
        Images: ``w = u`` (white dots on black) instead of ``w = 1 - u``. Maps: ``w = 1 - rescaled``.
    gamma : float
        Exponent applied to ``w`` after the above (``w**gamma``; > 1 lightens mid-tones).
    value_range : (float, float), optional
        ``.npy`` maps: the values sent to 0 and 1 (default: the map's minimum and maximum).
    levels : "auto" or (float, float), optional
        Images: the gray values ``(black, white)`` in [0, 1] stretched to black and white before the above
        (a levels adjustment); "auto": ``stipple.io.levels.auto_levels`` (the 0.5th and 99.5th percentiles, or
        the extremes where the percentiles would clip a feature). Default: none.
    strict : bool
        Refuse ``value_range`` for an image and ``levels`` for a map (one input: they would be ignored); False
        lets a batch of images and maps give each its own (``stipple batch``).

    Returns
    -------
    numpy.ndarray
        ``w`` in [0, 1], shape ``(rows, columns)``.
    """
    name = name or str(getattr(source, "name", source))
    _check_gamma(gamma)
    if value_range is not None:
        check_range(value_range)
    data = read_source(source)
    if not data:
        raise StippleError(f"{name}: file is empty")
    if data.startswith(NPY_MAGIC):
        if levels is not None and strict:
            raise StippleError(f"{name}: --levels is for images; a .npy map is stretched by --range")
        values = rescale(check_grid(load_array(data, name), name), value_range, name)
    else:
        if value_range is not None and strict:
            raise StippleError(f"{name}: --range is for .npy maps; an image's gray values are stretched by --levels")
        gray = check_grid(load_gray(data, name), name)
        values = 1.0 - stretch_levels(gray, levels)
        if levels is not None and np.any(gray < 1) and not np.any(values > 0):
            raise StippleError(
                f"{name}: no ink is left under --levels {_levels_text(levels)}: every pixel is at least as light as "
                "its white point (a lower WHITE, or --levels auto, keeps the image)"
            )
    density = _transfer(values, invert, gamma)
    if value_range is not None and not np.any(density > 0):
        # (--invert's own check names an all-zero density under it.)
        low, high = value_range
        raise StippleError(
            f"{name}: no density is left under --range {low:g} {high:g}: every value is at or below {low:g}"
        )
    if gamma != 1.0 and np.any(values > 0) and not np.any(density > 0):
        raise StippleError(
            f"{name}: no ink is left under --gamma {gamma:g}: every darkness rounds to 0 (try a smaller one)"
        )
    return density


def _levels_text(levels):
    """``levels`` as the user wrote them: "auto" or BLACK,WHITE."""
    return levels if levels == "auto" else ",".join(f"{value:g}" for value in levels)


def given_transfer(options):
    """The transfer options of ``load_density`` that ``options`` sets (``--invert`` on, ``--gamma`` not 1, a
    ``--range`` or ``--levels``), as the command line names them: the ones to refuse where they would be ignored."""
    given = {
        "--invert": bool(options.get("invert")),
        "--gamma": options.get("gamma") not in (None, 1.0),
        "--range": options.get("value_range") is not None,
        "--levels": options.get("levels") is not None,
    }
    return [flag for flag, on in given.items() if on]


def check_load_options(*, invert=False, gamma=1.0, value_range=None, levels=None, strict=True):
    """Raise if a setting of ``load_density`` is out of range (checked before any file is read)."""
    _check_gamma(gamma)
    if value_range is not None:
        check_range(value_range)
    check_levels(levels)


def image_density(image, *, invert=False, gamma=1.0, levels=None, name="input"):
    """Density ``w`` of a decoded PIL image, exactly as ``load_density`` makes it from an image file.

    Parameters
    ----------
    image : PIL.Image.Image
        A decoded picture (a video frame, say): gray values as ``load_gray`` reads them, alpha on white.
    invert, gamma, levels :
        As for ``load_density``.
    name : str
        What error messages call the picture.

    Returns
    -------
    numpy.ndarray
        ``w`` in [0, 1], shape ``(rows, columns)``: ``1 - u``, or ``u`` with ``invert``, to the power ``gamma``.
    """
    _check_gamma(gamma)
    return _transfer(1.0 - stretch_levels(check_grid(_gray_values(image, name), name), levels), invert, gamma)


def _check_gamma(gamma):
    if not is_real(gamma) or not gamma > 0 or not np.isfinite(gamma):
        raise StippleError(f"gamma must be a positive number, not {gamma}")


def _transfer(values, invert, gamma):
    """``values`` (dark = 1) as the density: inverted if asked, then to the power ``gamma``."""
    density = 1.0 - values if invert else values
    if invert and not np.any(density > 0):
        raise StippleError(
            "the input is blank under --invert (an image all black, a map at its top everywhere): --invert places "
            "dots on its light parts, and it has none"
        )
    return density**gamma if gamma != 1.0 else density


def load_colour(source, name=None):
    """Red, green and blue in [0, 1] of an image file, ``(H, W, 3)``, alpha composited on white paper.

    Gray images give three equal channels; EXIF orientation is applied and Pillow's decompression-bomb guard
    stays on, as for ``load_density``. ``.npy`` arrays are refused (colour needs an image).
    """
    source = source_or_stdin(source)
    name = name or str(getattr(source, "name", source))
    data = read_source(source)
    if not data:
        raise StippleError(f"{name}: file is empty")
    if data.startswith(NPY_MAGIC):
        raise StippleError(f"{name}: colour separation needs an image (PNG, JPEG, ...), not a .npy array")
    colour = image_colour(open_image(data, name, "not a supported image, or truncated"), name)
    check_grid(colour[..., 0], name)
    return colour


# Modes whose values Pillow's ``convert("RGBA")`` would clip or truncate to 8 bits: read as gray, then spread.
_DEEP_GRAY = ("I;16", "I;16B", "I;16L", "I;16N", "I", "F", "L", "1")


def image_colour(image, name="input"):
    """Red, green and blue in [0, 1] of a decoded PIL image, ``(H, W, 3)``, alpha composited on white.

    The one colour reader: gray images of every depth (8- and 16-bit, 32-bit integer, float) give three equal
    channels holding exactly ``load_gray``'s values, so that a picture has the same tone on the gray and the
    colour paths; RGB(A), palettes and the rest are decoded by Pillow.
    """
    if image.mode in _DEEP_GRAY:
        return np.repeat(_gray_values(image, name)[..., None], 3, axis=2)
    rgba = np.asarray(image.convert("RGBA"))
    if np.all(rgba[..., 3] == 255):  # opaque: the same values without the composite (a 12-megapixel photo's 2 s)
        return rgba[..., :3] / 255.0
    rgba = rgba / 255.0
    return rgba[..., :3] * rgba[..., 3:] + (1.0 - rgba[..., 3:])


def load_input(source, **options):
    """``load_density`` of a path, or of stdin when ``source`` is ``-``."""
    return load_density(source_or_stdin(source), **options)
