"""Colour separation: an RGB image as one ink density per class of dots, halftoned jointly.

Inks are subtractive and dots do not overlap, so the coverages of the classes add up: cyan, magenta and yellow
are ``c = 1 - R``, ``m = 1 - G``, ``y = 1 - B``; with black (``cmyk``) the grey component
``k = black * min(c, m, y)`` is taken out of all three (grey-component replacement, ``black = 1``: all of it).
The union of the classes then has the density ``c + m + y + k`` (``cmyk``) or ``c + m + y`` (``cmy``).
"""

from dataclasses import dataclass

import numpy as np

from .errors import StippleError
from .inputs import load_colour
from .multiclass import multiclass_problem, run

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


def colour_problem(rgb, n_points, bandwidth=None, *, separation="cmyk", black=1.0, union_weight=1.0, **options):
    """The joint halftoning problem of an RGB image's inks: ``(layers, problem)``.

    Parameters
    ----------
    rgb : numpy.ndarray or path
        ``(H, W, 3)`` colours in [0, 1], or an image file (``stipple.inputs.load_colour``).
    n_points : int
        Dots in all; each ink gets its share by mass (``stipple.multiclass.class_counts``).
    bandwidth : int, optional
        The union's bandwidth (see ``stipple.multiclass.multiclass_problem``).
    separation, black :
        See ``separate``.
    union_weight : float
        Factor of the union's term against the inks' (1: Wei's and Schmaltz et al.'s equal weights; 0: each
        ink alone, so dots of different inks may clump). A single ink has no union term.
    **options
        ``backend``, ``threads``, ``epsilon``, ``hessian``, ``near_field`` for every term.

    Returns
    -------
    tuple
        The layers that got dots (``Layer``, in the order of ``problem.slices``) and the ``MulticlassProblem``.
    """
    if not isinstance(rgb, np.ndarray):
        rgb = load_colour(rgb)
    layers = separate(rgb, separation, black)
    if not (np.isfinite(union_weight) and union_weight >= 0):
        raise StippleError(f"union weight must be a finite non-negative number, not {union_weight!r}")
    term_weights = [1.0] * len(layers) + [float(union_weight) if len(layers) > 1 else 0.0]
    problem = multiclass_problem(
        [layer.density for layer in layers],
        n_points,
        bandwidth,
        names=[layer.name for layer in layers],
        term_weights=term_weights,
        **options,
    )
    problem.settings.update(separation=separation, black=float(black))
    return [layer for layer in layers if layer.name in problem.names], problem


def halftone_colour(rgb, n_points, bandwidth=None, *, separation="cmyk", black=1.0, union_weight=1.0, **options):
    """Stipple an RGB image with one class of dots per ink: ``(layers, problem, result)``.

    Ink ``c``'s dots are ``result.points[problem.slices[c]]`` (unit coordinates, x right, y down). ``options``
    are ``colour_problem``'s and ``stipple.halftone.run``'s (``init``, ``seed``, ``tol``, ``iterations``, ...).
    """
    problem_keys = ("backend", "threads", "epsilon", "hessian", "near_field")
    problem_options = {key: options.pop(key) for key in problem_keys if key in options}
    layers, problem = colour_problem(
        rgb, n_points, bandwidth, separation=separation, black=black, union_weight=union_weight, **problem_options
    )
    return layers, problem, run(problem, **options)
