"""Checks of numbers where they enter the library: each error names the parameter and the values it allows."""

import numpy as np

from .errors import StippleError


def check_integer(name, value, low, high, *, even=False):
    """``value`` as an int if it is an integer in [low, high] (and even, if asked), else a StippleError."""
    integer = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
    if not integer or not low <= value <= high or (even and value % 2):
        kind = "an even integer" if even else "an integer"
        raise StippleError(f"{name} must be {kind} in [{low}, {high}], not {value!r}")
    return int(value)


def check_positive(name, value, allow_none=False):
    if value is None and allow_none:
        return None
    real = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    if not real or not np.isfinite(value) or value <= 0:
        raise StippleError(f"{name} must be a positive number, not {value!r}")
    return value
