"""Lengths and colours as users write them: ``200mm``, ``8in``, ``#1a2b3c``, ``navy``."""

import re

from ..errors import StippleError

UNITS = {"mm": 1.0, "cm": 10.0, "in": 25.4, "pt": 25.4 / 72, "px": 25.4 / 96}
MIN_LENGTH_MM = 1e-3
MAX_LENGTH_MM = 1e6
# A number in decimal notation, as SVG and CSV files write it: sign, ASCII digits with or without a point, exponent.
DECIMAL = r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?"
# A number given as text (a CSV cell, an option's value): decimal, or nan / inf, which the range checks after
# name. Python's float() and int() also read "1_0" as 10 and other scripts' digits (hostile sweeps).
NUMBER = re.compile(rf"\s*(?:{DECIMAL}|[-+]?(?:nan|inf|infinity))\s*", re.IGNORECASE)
INTEGER = re.compile(r"\s*[-+]?[0-9]+\s*")


def parse_number(text):
    """``float(text)`` for a number written as ``NUMBER`` allows; ValueError otherwise."""
    if not NUMBER.fullmatch(text):
        raise ValueError(f"not a number: {text!r}")
    return float(text)


def parse_length(text, name="length"):
    """``"200mm"``, ``"8in"``, ``"20 cm"``, ``"0.7pt"``, ``"800px"`` or a bare number (mm) -> (value, unit).

    The length must lie between ``MIN_LENGTH_MM`` (1 µm) and ``MAX_LENGTH_MM`` (1 km).
    """
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(mm|cm|in|pt|px)?\s*", str(text))
    allowed = f"a length (mm, cm, in, pt, px; a bare number is mm) from {MIN_LENGTH_MM:g}mm to {MAX_LENGTH_MM:g}mm"
    if not match:
        raise StippleError(f"{name} must be {allowed}, not {text!r}")
    value, unit = float(match.group(1)), match.group(2) or "mm"
    if not MIN_LENGTH_MM <= value * UNITS[unit] <= MAX_LENGTH_MM:
        raise StippleError(f"{name} must be {allowed}, not {text!r}")
    return value, unit


def to_user_units(length, physical_width, canvas_width):
    """A physical ``(value, unit)`` length in user units of a canvas ``physical_width`` wide."""
    value, unit = length
    width_value, width_unit = physical_width
    return value * UNITS[unit] / (width_value * UNITS[width_unit]) * canvas_width


WHITE, BLACK = (1.0, 1.0, 1.0), (0.0, 0.0, 0.0)


def hex_colour(colour):
    """``#rrggbb`` of an RGB triple in [0, 1]."""
    return "#" + "".join(f"{int(round(255 * channel)):02x}" for channel in colour)


def parse_colour(text, name="color"):
    """``#rrggbb``, ``#rgb`` or a CSS colour name (``white``, ``navy``) -> RGB in [0, 1]."""
    from PIL import ImageColor  # here: the command line loads this module, and not Pillow, for its numbers

    try:
        rgb = ImageColor.getrgb(str(text).strip())
    except ValueError:
        raise StippleError(f"{name} must be a colour such as #1a2b3c, #fff or white, not {text!r}") from None
    # Pillow passes rgb(999,2,3) and hsl(720,200%,50%) through out of range; an SVG then got fill="#3e70203".
    if not all(0 <= channel <= 255 for channel in rgb):
        raise StippleError(f"{name} must be a colour with channels from 0 to 255, not {text!r}")
    # #ff000080 and rgba(): the alpha was dropped without a word (a fifth sweep); inks and paper are opaque.
    if len(rgb) == 4 and rgb[3] != 255:
        raise StippleError(f"{name} must be an opaque colour (no alpha: inks and paper are drawn opaque), not {text!r}")
    return tuple(channel / 255 for channel in rgb[:3])
