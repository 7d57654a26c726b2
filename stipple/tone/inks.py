"""Inks that multiply: separations whose printed colour is the image's, and the colour inks print."""

import numpy as np

from ..errors import StippleError
from ..io.images import LUMA

# Each separation's inks, in their order (``stipple.colour.separate``'s layers and palette numbers, and here).
SEPARATION_INKS = {
    "cmyk": ("cyan", "magenta", "yellow", "black"),
    "cmy": ("cyan", "magenta", "yellow"),
    "gray": ("black",),
}
MULTIPLY_SEPARATIONS = tuple(SEPARATION_INKS)
INK_COLOURS = {
    "cyan": (0.0, 1.0, 1.0),
    "magenta": (1.0, 0.0, 1.0),
    "yellow": (1.0, 1.0, 0.0),
    "black": (0.0, 0.0, 0.0),
}


def multiply_separation(rgb, separation="cmyk"):
    """Ink coverages whose multiplied inks print an RGB image's colours: ``[(name, colour, coverage), ...]``.

    Parameters
    ----------
    rgb : numpy.ndarray
        ``(H, W, 3)`` red, green and blue in [0, 1] (white paper = 1).
    separation : {"cmyk", "cmy", "gray"}
        ``cmy``: ``c = 1 - R``, ``m = 1 - G``, ``y = 1 - B``; each channel is absorbed by one ink only, so the
        product is exact however the dots of different inks overlap. ``cmyk``: black ``k = 1 - max(R, G, B)``
        and ``c = 1 - R / (1 - k)`` etc. (zero for the brightest channel), so that ``(1 - c)(1 - k) = R``
        when cyan and black are laid independently. ``gray``: one black ink of coverage ``1 - luminance``
        (Rec. 601).

    Returns
    -------
    list of (str, tuple, numpy.ndarray)
        Ink name, ink colour (RGB in [0, 1]) and coverage ``(H, W)`` in [0, 1], in the order cyan, magenta,
        yellow, black (the inks of ``stipple.colour.separate``, which has the same support per ink). Inks with
        no coverage anywhere are kept (all zero), so the list always has 4, 3 or 1 entries.

    Notes
    -----
    ``stipple.colour.separate`` takes ``k = min(c, m, y)`` and ``c - k`` etc. for inks that never overlap
    (coverages add); once the inks overlap and multiply, its red reflectance is ``(1 - c + k)(1 - k)``, lighter
    than ``R = 1 - c`` by ``(c - k) k``: mid-dark saturated colours come out washed out.
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise StippleError(f"rgb must have shape (H, W, 3), not {rgb.shape}")
    if not np.all(np.isfinite(rgb)) or rgb.min() < 0 or rgb.max() > 1:
        raise StippleError("rgb values must be finite and in [0, 1]")
    if separation not in MULTIPLY_SEPARATIONS:
        raise StippleError(f"separation must be one of {', '.join(MULTIPLY_SEPARATIONS)}, not {separation!r}")
    if separation == "gray":
        return [("black", INK_COLOURS["black"], np.clip(1.0 - rgb @ LUMA, 0.0, 1.0))]
    names = SEPARATION_INKS["cmy"]
    if separation == "cmy":
        return [(name, INK_COLOURS[name], 1.0 - rgb[..., i]) for i, name in enumerate(names)]
    brightest = rgb.max(axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        inks = np.where(brightest[..., None] > 0, 1.0 - rgb / brightest[..., None], 0.0)
    layers = [(name, INK_COLOURS[name], np.clip(inks[..., i], 0.0, 1.0)) for i, name in enumerate(names)]
    return layers + [("black", INK_COLOURS["black"], 1.0 - brightest)]


def multiply_colour(coverages, colours):
    """The mean colour of inks laid independently and multiplied: ``prod_k (1 - a_k (1 - p_k))`` per channel.

    Parameters
    ----------
    coverages : list of numpy.ndarray
        Each ink's coverage ``(H, W)`` in [0, 1].
    colours : list of tuple
        Each ink's colour, RGB in [0, 1].

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` reflectance in [0, 1].
    """
    if len(coverages) != len(colours) or not coverages:
        raise StippleError("coverages and colours must be non-empty lists of the same length")
    shape = np.shape(coverages[0])
    result = np.ones((*shape, 3))
    for coverage, colour in zip(coverages, colours, strict=True):
        a = np.asarray(coverage, dtype=np.float64)
        if a.shape != shape:
            raise StippleError(f"coverages must all have the shape {shape}, not {a.shape}")
        result *= 1.0 - a[..., None] * (1.0 - np.asarray(colour, dtype=np.float64))
    return result
