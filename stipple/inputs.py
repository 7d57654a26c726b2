"""Reading images and numeric maps into densities ``w >= 0`` (dark = many dots)."""

import io
import warnings

import numpy as np
from PIL import Image, ImageOps, UnidentifiedImageError

from .errors import StippleError

NPY_MAGIC = b"\x93NUMPY"
_LUMA = np.array([0.299, 0.587, 0.114])


def read_source(source):
    """Bytes of ``source``: a path, or a binary file object (``-`` in the CLI is stdin)."""
    try:
        if hasattr(source, "read"):
            return source.read()
        with open(source, "rb") as handle:
            return handle.read()
    except OSError as error:
        raise StippleError(f"cannot read {source}: {error.strerror or error}") from None


def load_gray(data, name="input"):
    """Gray values ``u`` in [0, 1] (0 = black) of an image file's bytes; alpha is composited on white.

    PNG, JPEG, TIFF and anything else Pillow opens; 8- and 16-bit gray, RGB(A), palettes. EXIF
    orientation is applied. Pillow's decompression-bomb guard stays on.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            image = Image.open(io.BytesIO(data))
            image.load()
    except (Image.DecompressionBombError, Image.DecompressionBombWarning):
        raise StippleError(f"{name}: image is too large (Pillow's decompression-bomb guard)") from None
    except UnidentifiedImageError:
        raise StippleError(f"{name}: cannot decode image (not a supported image or .npy file, or truncated)") from None
    except (OSError, SyntaxError, ValueError) as error:
        raise StippleError(f"{name}: cannot decode image ({error})") from None
    image = ImageOps.exif_transpose(image)
    return _gray_values(image)


def _gray_values(image):
    if image.mode in ("I;16", "I;16B", "I;16L", "I;16N"):
        return np.asarray(image, dtype=np.float64) / 65535.0
    if image.mode == "I":
        values = np.asarray(image, dtype=np.float64)
        return values / (65535.0 if values.max(initial=0) > 255 else 255.0)
    if image.mode == "F":
        return np.clip(np.asarray(image, dtype=np.float64), 0.0, 1.0)
    if image.mode in ("L", "1"):
        return np.asarray(image.convert("L"), dtype=np.float64) / 255.0
    rgba = np.asarray(image.convert("RGBA"), dtype=np.float64) / 255.0
    alpha = rgba[..., 3]
    return (rgba[..., :3] @ _LUMA) * alpha + (1.0 - alpha)


def load_array(data, name="input"):
    """A numeric 2-D array from ``.npy`` bytes; object arrays are refused (nothing is unpickled)."""
    try:
        array = np.load(io.BytesIO(data), allow_pickle=False)
    except ValueError as error:
        if "pickle" in str(error).lower():
            raise StippleError(f"{name}: .npy holds Python objects; only numeric arrays are read") from None
        raise StippleError(f"{name}: corrupt or truncated .npy file ({error})") from None
    except (OSError, EOFError) as error:
        raise StippleError(f"{name}: corrupt or truncated .npy file ({error})") from None
    if not np.issubdtype(array.dtype, np.number) or np.issubdtype(array.dtype, np.complexfloating):
        raise StippleError(f"{name}: .npy must hold real numbers, not {array.dtype}")
    return array.astype(np.float64)


def check_grid(values, name="input"):
    """Raise unless ``values`` is a finite 2-D grid of at least 2×2 cells."""
    if values.ndim != 2:
        raise StippleError(f"{name}: expected a 2-D map, got shape {values.shape}")
    if min(values.shape) < 2:
        raise StippleError(f"{name}: map must be at least 2×2 cells, got {values.shape[0]}×{values.shape[1]}")
    if not np.all(np.isfinite(values)):
        raise StippleError(f"{name}: map contains NaN or infinite values")
    return values


def rescale(values, value_range=None, name="input"):
    """Linear map of ``value_range`` (default: the data's min and max) onto [0, 1], clipped."""
    low, high = value_range if value_range is not None else (values.min(), values.max())
    if not high > low:
        raise StippleError(f"{name}: map is constant ({low:g}); nothing to rescale (give a range)")
    # Halving first keeps high - low finite for values near the float64 limits.
    return np.clip((values / 2 - low / 2) / (high / 2 - low / 2), 0.0, 1.0)


def load_density(source, *, invert=False, gamma=1.0, value_range=None, name=None):
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

    Returns
    -------
    numpy.ndarray
        ``w`` in [0, 1], shape ``(rows, columns)``.
    """
    name = name or str(getattr(source, "name", source))
    if not gamma > 0 or not np.isfinite(gamma):
        raise StippleError(f"gamma must be a positive number, not {gamma}")
    data = read_source(source)
    if not data:
        raise StippleError(f"{name}: file is empty")
    if data.startswith(NPY_MAGIC):
        values = rescale(check_grid(load_array(data, name), name), value_range, name)
    else:
        values = 1.0 - check_grid(load_gray(data, name), name)
    density = 1.0 - values if invert else values
    return density**gamma if gamma != 1.0 else density


def read_points_csv(source, names):
    """Columns ``names`` of a CSV with a header row (as written by stipple) as an ``(M, len(names))`` array."""
    name = str(getattr(source, "name", source))
    text = read_source(source).decode("utf-8", errors="replace")
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    if not lines:
        raise StippleError(f"{name}: empty points file")
    header = [column.strip().lower() for column in lines[0].split(",")]
    missing = [column for column in names if column not in header]
    if missing:
        raise StippleError(f"{name}: expected CSV columns {','.join(names)}, got {lines[0]!r}")
    indices = [header.index(column) for column in names]
    try:
        rows = [[float(line.split(",")[i]) for i in indices] for line in lines[1:]]
    except (ValueError, IndexError):
        raise StippleError(f"{name}: malformed CSV row") from None
    points = np.array(rows, dtype=np.float64).reshape(-1, len(names))
    if len(points) == 0:
        raise StippleError(f"{name}: no points")
    if not np.all(np.isfinite(points)):
        raise StippleError(f"{name}: points contain NaN or infinite values")
    return points


def load_colour(source, name=None):
    """Red, green and blue in [0, 1] of an image file, ``(H, W, 3)``, alpha composited on white paper.

    Gray images give three equal channels; EXIF orientation is applied and Pillow's decompression-bomb guard
    stays on, as for ``load_density``. ``.npy`` arrays are refused (colour needs an image).
    """
    name = name or str(getattr(source, "name", source))
    data = read_source(source)
    if not data:
        raise StippleError(f"{name}: file is empty")
    if data.startswith(NPY_MAGIC):
        raise StippleError(f"{name}: colour separation needs an image (PNG, JPEG, ...), not a .npy array")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            image = Image.open(io.BytesIO(data))
            image.load()
    except (Image.DecompressionBombError, Image.DecompressionBombWarning):
        raise StippleError(f"{name}: image is too large (Pillow's decompression-bomb guard)") from None
    except UnidentifiedImageError:
        raise StippleError(f"{name}: cannot decode image (not a supported image, or truncated)") from None
    except (OSError, SyntaxError, ValueError) as error:
        raise StippleError(f"{name}: cannot decode image ({error})") from None
    rgba = np.asarray(ImageOps.exif_transpose(image).convert("RGBA"), dtype=np.float64) / 255.0
    colour = rgba[..., :3] * rgba[..., 3:] + (1.0 - rgba[..., 3:])
    check_grid(colour[..., 0], name)
    return colour
