"""Colour separation: an RGB image as one ink density per class of dots, and the dots each class gets.

Inks are subtractive and dots do not overlap, so the coverages of the classes add up: cyan, magenta and yellow
are ``c = 1 - R``, ``m = 1 - G``, ``y = 1 - B``; with black (``cmyk``) the grey component
``k = black * min(c, m, y)`` is taken out of all three (grey-component replacement, ``black = 1``: all of it).
The union of the classes then has the density ``c + m + y + k`` (``cmyk``) or ``c + m + y`` (``cmy``).
"""

from dataclasses import dataclass

import numpy as np

from .errors import StippleError

SEPARATIONS = ("cmyk", "cmy", "gray")
INK_COLOURS = {
    "cyan": (0.0, 1.0, 1.0),
    "magenta": (1.0, 0.0, 1.0),
    "yellow": (1.0, 1.0, 0.0),
    "black": (0.0, 0.0, 0.0),
}
_LUMA = np.array([0.299, 0.587, 0.114])


@dataclass
class Layer:
    """One class of dots: an ink's name, its colour (RGB in [0, 1]) and its density ``w >= 0`` on the pixels."""

    name: str
    colour: tuple
    density: np.ndarray


def separate(rgb, separation="cmyk", black=1.0):
    """Ink densities of an RGB image (rows top to bottom, values in [0, 1], white paper = 1).

    Parameters
    ----------
    rgb : numpy.ndarray
        ``(H, W, 3)`` array of red, green and blue in [0, 1].
    separation : {"cmyk", "cmy", "gray"}
        Inks: cyan, magenta, yellow and black; the three colours only; or one black ink of density
        ``1 - luminance`` (Rec. 601), the classic single-class stipple.
    black : float
        Fraction in [0, 1] of the grey component ``min(c, m, y)`` that black replaces (``cmyk`` only).

    Returns
    -------
    list of Layer
        One layer per ink, in the order cyan, magenta, yellow, black; inks with no mass are left out.
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise StippleError(f"colour image must have shape (H, W, 3), not {rgb.shape}")
    if not np.all(np.isfinite(rgb)) or rgb.min() < 0 or rgb.max() > 1:
        raise StippleError("colour values must be finite and in [0, 1]")
    if separation not in SEPARATIONS:
        raise StippleError(f"separation must be one of {', '.join(SEPARATIONS)}, not {separation!r}")
    if not 0 <= black <= 1:
        raise StippleError(f"black must be in [0, 1], not {black!r}")
    if separation == "gray":
        densities = {"black": 1.0 - rgb @ _LUMA}
    else:
        inks = 1.0 - rgb
        grey = black * inks.min(axis=2) if separation == "cmyk" else np.zeros(rgb.shape[:2])
        densities = {name: inks[..., index] - grey for index, name in enumerate(("cyan", "magenta", "yellow"))}
        densities["black"] = grey
    layers = [Layer(name, INK_COLOURS[name], np.maximum(value, 0.0)) for name, value in densities.items()]
    layers = [layer for layer in layers if layer.density.sum() > 0]
    if not layers:
        raise StippleError("the image is blank (all white): there is nothing to place dots on")
    return layers


def class_counts(masses, total):
    """Dots per class in proportion to the masses, rounded by largest remainder (Hamilton's method).

    Every count is the quota ``total * mass / sum(masses)`` rounded down or up, and the counts add up to
    ``total``; the remainders are handed out largest first (ties to the earlier class).

    Parameters
    ----------
    masses : sequence of float
        Non-negative masses, at least one positive.
    total : int
        Number of dots to share out.

    Returns
    -------
    numpy.ndarray
        Integer counts, one per class.
    """
    masses = np.asarray(masses, dtype=np.float64)
    if masses.ndim != 1 or np.any(masses < 0) or not masses.sum() > 0 or not np.all(np.isfinite(masses)):
        raise StippleError("class masses must be finite, non-negative and not all zero")
    quotas = total * masses / masses.sum()
    counts = np.floor(quotas).astype(int)
    remainders = quotas - counts
    order = np.argsort(-remainders, kind="stable")
    counts[order[: total - counts.sum()]] += 1
    return counts
