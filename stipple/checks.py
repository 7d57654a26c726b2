"""Checks of numbers where they enter the library: each error names the parameter and the values it allows."""

import os

import numpy as np

from .errors import StippleError

# The most iterations a run, a restart cycle, a checkpoint's cadence or a saved state may count.
MAX_ITERATIONS = 10**9


def check_integer(name, value, low, high, *, even=False):
    """``value`` as an int if it is an integer in [low, high] (and even, if asked), else a StippleError."""
    integer = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
    if not integer or not low <= value <= high or (even and value % 2):
        kind = "an even integer" if even else "an integer"
        raise StippleError(f"{name} must be {kind} in [{low}, {high}], not {value!r}")
    return int(value)


def is_real(value):
    """Whether ``value`` is one real number (Python's or numpy's; not a bool, a complex number or a string)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def check_positive(name, value, allow_none=False):
    if value is None and allow_none:
        return None
    if not is_real(value) or not np.isfinite(value) or value <= 0:
        raise StippleError(f"{name} must be a positive number, not {value!r}")
    return value


def check_hooks(callback, checkpoint):
    """Raise unless ``callback`` is callable (or None) and ``checkpoint`` a file's path (or None): 5 failed at
    the first call, a number or bytes as a checkpoint in os's words, and a folder was "an existing checkpoint"."""
    if callback is not None and not callable(callback):
        raise StippleError(f"callback must be a function of the CG state, not {callback!r}")
    if checkpoint is not None and (not isinstance(checkpoint, (str, os.PathLike)) or os.path.isdir(checkpoint)):
        raise StippleError(f"checkpoint must be the path of a file, not {checkpoint!r}")


def two_numbers(pair, name, form):
    """``pair`` as two floats, or a StippleError naming ``name`` and its ``form`` (5, (1, 2, 3) and ("a", "b")
    failed in Python's words)."""
    try:
        first, second = (float(value) for value in pair)
    except (TypeError, ValueError):
        raise StippleError(f"{name} must be two numbers {form}, not {pair!r}") from None
    return first, second
