"""Gray levels: ``--levels`` checked and applied, ``--levels auto``'s choice (percentiles, or robust extremes where
they would clip a feature) and the hint for a faint image."""

import numpy as np

from ..checks import two_numbers
from ..errors import StippleError


def stretch_levels(gray, levels):
    """Gray values with ``levels = (black, white)`` (or "auto": ``auto_levels``) sent to 0 and 1,
    linearly, clipped; unchanged for None (see ``load_density``)."""
    if levels is None:
        return gray
    if levels == "auto":
        black, white = auto_levels(gray)
    else:
        black, white = check_levels(levels)
    return np.clip((gray - black) / (white - black), 0.0, 1.0)


def auto_levels(gray, what="the image"):
    """``(black, white)`` that ``--levels auto`` stretches to 0 and 1: the 0.5th and 99.5th percentiles, which
    leave out a scan's specks and noise, or the extremes (``robust_extremes``) where the percentiles would clip a
    feature (``feature_extremes``); a StippleError naming ``what`` where ``gray`` has one value."""
    low, high = np.percentile(gray, [0.5, 99.5])
    low, high = feature_extremes(gray, low, high) or (low, high)
    if not low < high:
        raise StippleError(f"--levels auto: {what} has one gray value ({low:.3g}); nothing to stretch")
    return float(low), float(high)


# A plain page with marks: fewer than this share of its pixels differ from its gray by more than their noise.
PLAIN_SHARE = 0.02
# A faint image's gray values span more than this many times its pixels' noise (a plain gray's noise is no
# picture) and at least this share of the range, about 13 8-bit steps: stretched, a span of a few steps shows them
# as bands (a held-out light gray of 0.85 +- 0.01, five steps, came out dark and banded under --levels auto), while
# a photo mapped to 0.86-1 (24 steps) came out clean and got no hint at 0.1.
NOISE_SPANS, FAINT_LEAST = 8.0, 0.05


# Where a region of at least 3 x 3 pixels reaches beyond the percentiles by more than this share of their span,
# they clip a feature. Photos reach 0.01-0.19 of it (held-out and bundled ones); a few narrow peaks on an empty
# field 1.2 (their cores are under 0.5 % of the pixels: stretched, each peak became a black disc).
FEATURE_REACH = 0.5


def feature_extremes(values, low, high):
    """``robust_extremes`` where what lies beyond ``[low, high]`` is a feature that the percentiles would clip and
    widen (a small dark spot on a plain page became a black disc), else None: it differs from the rest more than the
    rest varies within it; or the rest is a plain page (``plain_page``) and it reaches farther beyond than
    ``high - low`` (a soft spot, whose tail varies within); or more than a scan's specks (``robust_extremes``)
    reach beyond by more than ``FEATURE_REACH`` of ``high - low`` (narrow peaks, whose tails vary within and leave
    no plain page). The 3 x 3 median runs once, and for the last test only where the plain extremes reach that far
    (it takes seconds on a large photo)."""
    beyond = np.sum(np.maximum(values - high, 0.0)) + np.sum(np.maximum(low - values, 0.0))
    if not beyond > 0:
        return None
    within = np.clip(values, low, high)
    reach = max(np.max(values) - high, low - np.min(values))
    if beyond > np.sum(np.abs(within - np.median(within))) or (reach > high - low and plain_page(values)):
        return robust_extremes(values)
    if not reach > FEATURE_REACH * (high - low):
        return None
    robust_low, robust_high = robust_extremes(values)
    reaches = max(robust_high - high, low - robust_low) > FEATURE_REACH * (high - low)
    return (robust_low, robust_high) if reaches else None


def robust_extremes(values):
    """The least and greatest of ``values`` filtered by a 3 x 3 median, which leaves out a scan's specks of up to
    2 x 2 pixels (one speck on a sparse faint sketch set the plain extremes, and the stretch did nothing), or the
    plain extremes where nothing else is left (one small mark on a plain page)."""
    from scipy import ndimage

    filtered = ndimage.median_filter(values, size=3, mode="nearest")
    low, high = float(filtered.min()), float(filtered.max())
    return (low, high) if low < high else (float(np.min(values)), float(np.max(values)))


def plain_page(values):
    """Whether all but ``PLAIN_SHARE`` of the pixels lie within three times their noise (``pixel_noise``; at least
    one 8-bit step) of the median gray."""
    tolerance = max(3 * pixel_noise(values), 1 / 255)
    return bool(np.mean(np.abs(values - np.median(values)) > tolerance) < PLAIN_SHARE)


def pixel_noise(values):
    """The pixels' noise: the standard deviation that the median absolute difference of neighbouring pixels implies
    (edges and smooth gradients hardly count; 0 on a plain page), from about 2^22 differences along each axis."""
    step = -(-values.size // 2**22)
    differences = np.concatenate([np.diff(values[::step], axis=1).ravel(), np.diff(values[:, ::step], axis=0).ravel()])
    if differences.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(differences)) / np.sqrt(2))


def faint_span(values, widest):
    """The span that ``--levels auto`` would stretch (``auto_levels``) where that helps, else None: less than
    ``widest``, at least ``FAINT_LEAST`` and more than ``NOISE_SPANS`` times the pixels' noise (stretched, a plain
    gray's noise became a dark speckle). A spot on a plain page spans the whole range there: no hint."""
    try:
        black, white = auto_levels(values)
    except StippleError:  # one gray value
        return None
    span = white - black
    return span if FAINT_LEAST <= span < widest and span > NOISE_SPANS * pixel_noise(values) else None


def check_levels(levels):
    """``levels`` (None, "auto" or ``(black, white)`` with ``0 <= black < white <= 1``), checked."""
    if levels is None or levels == "auto":
        return levels
    if isinstance(levels, str):
        raise StippleError(f"levels must be 'auto' or BLACK,WHITE, not {levels!r}")
    black, white = two_numbers(levels, "levels", "BLACK,WHITE")
    if not (np.isfinite(black) and np.isfinite(white) and 0 <= black < white <= 1):
        raise StippleError(f"levels must be BLACK,WHITE with 0 <= BLACK < WHITE <= 1, not {black:g},{white:g}")
    return black, white
