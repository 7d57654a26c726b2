"""Argument checks of ``stipple.tone``: each error names the parameter and the values it allows."""

import numpy as np

from ..checks import check_integer
from ..errors import StippleError


def check_discs(centres, radii):
    centres = np.asarray(centres, dtype=np.float64)
    if centres.ndim != 2 or centres.shape[1] != 2:
        raise StippleError(f"centres must have shape (N, 2), not {centres.shape}")
    if not np.all(np.isfinite(centres)):
        raise StippleError("centres must be finite")
    if radii is not None:
        radii = np.asarray(radii, dtype=np.float64)
        if radii.shape != (len(centres),):
            raise StippleError(f"radii must have shape ({len(centres)},), not {radii.shape}")
        if not np.all(np.isfinite(radii)) or np.any(radii < 0):
            raise StippleError("radii must be finite and >= 0")
    return centres, radii


def check_size(size):
    try:
        width, height = (float(v) for v in size)
    except (TypeError, ValueError):
        raise StippleError(f"size must be (width, height), two positive numbers, not {size!r}") from None
    if not (np.isfinite(width) and np.isfinite(height) and width > 0 and height > 0):
        raise StippleError(f"size must be (width, height), two positive numbers, not {size!r}")
    return width, height


def check_darkness(darkness, name="darkness"):
    darkness = np.asarray(darkness, dtype=np.float64)
    if darkness.ndim != 2 or min(darkness.shape) < 1:
        raise StippleError(f"{name} must be a 2-d image (H, W), not shape {darkness.shape}")
    if not np.all(np.isfinite(darkness)) or darkness.min() < 0 or darkness.max() > 1:
        raise StippleError(f"{name} must be finite and in [0, 1]")
    return darkness


def check_colours(colours, count):
    """Each ink's absorptance ``1 - colour``, ``(count, 3)``."""
    try:
        values = np.asarray(colours, dtype=np.float64)
    except (TypeError, ValueError):
        values = np.zeros(0)
    if values.shape != (count, 3) or not np.all(np.isfinite(values)) or values.min() < 0 or values.max() > 1:
        raise StippleError(f"colours must be {count} RGB triples in [0, 1], one per layer")
    return 1.0 - values


def check_options(passes, samples_per_dot, min_radius, max_radius, max_ratio):
    passes = check_integer("passes", passes, 0, 50)
    samples_per_dot = check_integer("samples_per_dot", samples_per_dot, 4, 1024)
    return passes, samples_per_dot, check_bounds(min_radius, max_radius, max_ratio)


def check_bounds(min_radius, max_radius, max_ratio):
    if not (np.isfinite(min_radius) and min_radius >= 0):
        raise StippleError(f"min_radius must be a finite number >= 0, not {min_radius!r}")
    if max_radius is not None and not (np.isfinite(max_radius) and max_radius > 0 and max_radius >= min_radius):
        raise StippleError(f"max_radius must be a finite number > 0 and >= min_radius, not {max_radius!r}")
    if not (np.isfinite(max_ratio) and 0 < max_ratio <= 10):
        raise StippleError(f"max_ratio must be in (0, 10], not {max_ratio!r}")
    return float(min_radius), (None if max_radius is None else float(max_radius)), float(max_ratio)
