"""Colour separation: an RGB image as one ink density per class of dots, halftoned jointly.

Inks are subtractive and dots do not overlap, so the coverages of the classes add up: cyan, magenta and yellow
are ``c = 1 - R``, ``m = 1 - G``, ``y = 1 - B``; with black (``cmyk``) the grey component
``k = black * min(c, m, y)`` is taken out of all three (grey-component replacement, ``black = 1``: all of it).
The union of the classes then has the density ``c + m + y + k`` (``cmyk``) or ``c + m + y`` (``cmy``).

A palette of pen colours ``p_k`` (RGB reflectances in [0, 1]) is separated in the same subtractive model of
dots that do not overlap (Murray-Davies / Neugebauer with the pens as the only primaries): paper of
reflectance 1 with coverages ``a_k`` reflects ``1 - sum_k a_k (1 - p_k)`` in each channel, so a pixel's
absorptance ``1 - rgb`` is ``A a`` with the columns ``A_k = 1 - p_k``. Per pixel, ``a >= 0`` minimises
``|A a - (1 - rgb)|^2 + TIE_BREAK * (sum_k a_k)^2`` (non-negative least squares; the small second term picks the
least ink among equal fits, so grey takes the black pen rather than three colours), and coverages adding up to
more than 1 are scaled down to 1. With the pens cyan, magenta, yellow and black this is close to ``cmyk``.
"""

from dataclasses import dataclass, replace
from itertools import combinations

import numpy as np

from .errors import StippleError
from .io.images import LUMA, load_colour
from .multiclass import multiclass_problem, run
from .tone.inks import INK_COLOURS, SEPARATION_INKS

SEPARATIONS = tuple(SEPARATION_INKS)
TIE_BREAK = 1e-3
MAX_PENS = 8
MIN_ABSORPTANCE = 0.05
# Darkness below this is the rounding of a sum of weights (white paper), not ink.
ROUNDING = 1e-12
# The union term's weight against each ink's: beyond this the inks' own terms are rounding in the sum
# (1e300 overflowed to a NaN step, 1e150 to a RuntimeWarning).
MAX_UNION_WEIGHT = 1e6


def parse_palette(text):
    """``cmyk``, ``cmy``, ``gray`` or a comma-separated list of pen colours (``#00a0e0``, ``#fff``, CSS names).

    Returns the separation's name, or a list of ``(name, rgb)`` pens (the name is the colour as given).
    """
    from .io.units import parse_colour

    text = str(text).strip()
    if text.lower() in SEPARATIONS:
        return text.lower()
    names = [part.strip() for part in text.split(",")]
    if not 1 <= len(names) <= MAX_PENS or not all(names):
        raise StippleError(
            f"palette must be one of {', '.join(SEPARATIONS)} or 1 to {MAX_PENS} comma-separated pen colours, "
            f"not {text!r}"
        )
    pens = [(name, parse_colour(name, "palette colour")) for name in names]
    for name, rgb in pens:
        if np.max(1.0 - np.asarray(rgb)) < MIN_ABSORPTANCE:
            raise StippleError(f"palette colour {name!r} is too close to the white paper to draw with")
    if len({rgb for _, rgb in pens}) < len(pens):
        raise StippleError(f"palette colours must differ from each other, not {text!r}")
    return pens


def pen_coverages(rgb, pens):
    """Per-pixel coverage of each pen (see the module's docstring): an ``(H, W, K)`` array in [0, 1].

    Exact non-negative least squares, vectorised: the solution is the unconstrained least-squares fit on its
    support, so every support (at most ``2**K - 1`` of them) is solved for all pixels at once and each pixel
    keeps the best fit that is non-negative.
    """
    absorb = 1.0 - np.asarray([colour for _, colour in pens], dtype=np.float64).T  # (3, K)
    system = np.vstack([absorb, np.sqrt(TIE_BREAK) * np.ones((1, absorb.shape[1]))])  # (4, K)
    target = np.concatenate([1.0 - rgb.reshape(-1, 3), np.zeros((rgb.shape[0] * rgb.shape[1], 1))], axis=1).T
    best = np.zeros((absorb.shape[1], target.shape[1]))
    best_residual = np.sum(target**2, axis=0)
    for size in range(1, absorb.shape[1] + 1):
        for support in combinations(range(absorb.shape[1]), size):
            columns = system[:, support]
            fit = np.linalg.lstsq(columns, target, rcond=None)[0]
            residual = np.sum((columns @ fit - target) ** 2, axis=0)
            better = np.all(fit >= -1e-12, axis=0) & (residual < best_residual - 1e-15)
            best[:, better] = 0.0
            best[np.ix_(support, better.nonzero()[0])] = np.maximum(fit[:, better], 0.0)
            best_residual = np.where(better, residual, best_residual)
    coverage = best.T.reshape(rgb.shape[0], rgb.shape[1], -1)
    total = coverage.sum(axis=2, keepdims=True)
    return np.clip(coverage / np.maximum(total, 1.0), 0.0, 1.0)


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
    separation : {"cmyk", "cmy", "gray"} or list of (name, rgb)
        Inks: cyan, magenta, yellow and black; the three colours only; one black ink of density
        ``1 - luminance`` (Rec. 601), the classic single-class stipple; or pens (``parse_palette``), separated by
        ``pen_coverages``.
    black : float
        Fraction in [0, 1] of the grey component ``min(c, m, y)`` that black replaces (``cmyk`` only).

    Returns
    -------
    list of Layer
        One layer per ink, in the order cyan, magenta, yellow, black (or the pens'); inks with no mass are left out.
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise StippleError(f"colour image must have shape (H, W, 3), not {rgb.shape}")
    if not np.all(np.isfinite(rgb)) or rgb.min() < 0 or rgb.max() > 1:
        raise StippleError("colour values must be finite and in [0, 1]")
    if not isinstance(separation, str):
        coverage = pen_coverages(rgb, separation)
        layers = [Layer(name, colour, coverage[..., k]) for k, (name, colour) in enumerate(separation)]
        if not np.any(1.0 - rgb > ROUNDING):
            return _with_mass(layers)
        names = ", ".join(name for name, _ in separation)
        why = f"the inks {names} print none of the image's colours (each would darken a colour the image does not have)"
        return _with_mass(layers, why)
    if separation not in SEPARATIONS:
        raise StippleError(f"separation must be one of {', '.join(SEPARATIONS)}, not {separation!r}")
    if not 0 <= black <= 1:
        raise StippleError(f"black must be in [0, 1], not {black!r}")
    if separation == "gray":
        # White's luminance sums the weights to 1 - 1.1e-16: below ROUNDING the paper is white.
        darkness = 1.0 - rgb @ LUMA
        densities = {"black": np.where(darkness < ROUNDING, 0.0, darkness)}
    else:
        inks = 1.0 - rgb
        grey = black * inks.min(axis=2) if separation == "cmyk" else np.zeros(rgb.shape[:2])
        densities = {name: inks[..., index] - grey for index, name in enumerate(SEPARATION_INKS["cmy"])}
        densities["black"] = grey
    return _with_mass([Layer(name, INK_COLOURS[name], np.maximum(value, 0.0)) for name, value in densities.items()])


def print_target(rgb, separation):
    """The colour that the inks of ``separation`` are to print for ``rgb``: the image itself, but for "gray" its
    luminance in all three channels (one black ink cannot print a colour, and its tone matched to the image's
    colour channels equally would be ``1 - mean(R, G, B)``, a saturated blue drawn 0.34 for luminance 0.20)."""
    rgb = np.asarray(rgb, dtype=np.float64)
    if isinstance(separation, str) and separation == "gray":
        return np.repeat((rgb @ LUMA)[..., None], 3, axis=2)
    return rgb


def _with_mass(layers, nothing="the image is blank (all white)"):
    """The layers that have ink; an error if none has, saying why (``nothing``)."""
    layers = [layer for layer in layers if layer.density.sum() > 0]
    if not layers:
        raise StippleError(f"{nothing}: there is nothing to place dots on")
    return layers


def palette_inks(separation):
    """The names of ``separation``'s inks in its order (``separate``'s, before inks without mass are left out)."""
    if not isinstance(separation, str):
        return [name for name, _ in separation]
    return list(SEPARATION_INKS.get(separation, SEPARATION_INKS["cmyk"]))


def palette_number(separation, name):
    """Ink ``name``'s number in ``separation``'s palette, from 1: its SVG layer and vpype layer, kept free where
    an ink gets no dots so that every pen keeps its slot."""
    return palette_inks(separation).index(name) + 1


def check_palette_extras(palette, black, union_weight=1.0):
    """Refuse ``--black`` and ``--union-weight`` where they would be ignored: without ``--palette`` (both),
    ``--black`` with a palette other than cmyk (the only one with a black ink for the grey component), and
    ``--union-weight`` with one ink (gray, or one pen colour: the union is that ink)."""
    inks = None if palette is None else parse_palette(palette)
    one_ink = inks == "gray" or (isinstance(inks, list) and len(inks) == 1)
    if one_ink and union_weight != 1.0:
        raise StippleError(f"--union-weight is for several inks, not --palette {palette}: it would be ignored")
    if palette is None:
        given = [name for name, value in (("--black", black), ("--union-weight", union_weight)) if value != 1.0]
        if given:
            raise StippleError(f"{' and '.join(given)}: for runs with --palette; without it they would be ignored")
    elif black != 1.0 and inks != "cmyk":
        raise StippleError(
            f"--black is for --palette cmyk (its black ink), not --palette {palette}: it would be ignored"
        )


def check_union_weight(union_weight):
    """Raise unless the union's weight is a number in [0, MAX_UNION_WEIGHT]."""
    if not (np.isfinite(union_weight) and 0 <= union_weight <= MAX_UNION_WEIGHT):
        raise StippleError(f"--union-weight must be a number in [0, {MAX_UNION_WEIGHT:g}], not {union_weight!r}")


def union_darkness(layers):
    """The inks' darkness together, ``(H, W)`` in [0, 1]: what one pen drawing every ink lays down."""
    return np.clip(sum(layer.density for layer in layers), 0.0, 1.0)


def check_layer_names(names, layers, separation, where="the image"):
    """An error naming the layer ``names`` that are not inks of ``layers`` (``separate``'s of ``where`` into
    ``separation``): saved layered points drawn or judged against the wrong image or palette."""
    inks = [layer.name for layer in layers]
    unknown = [name for name in dict.fromkeys(names) if name not in inks]
    if unknown:
        raise StippleError(
            f"layers {', '.join(unknown)} are not inks of --palette {palette_label(separation)} for {where} (its "
            f"inks there: {', '.join(inks)}): is it the colour image the points were made from, with their "
            "palette and --black?"
        )


def palette_label(separation):
    """The separation as text: its name, or the pens' colours joined by commas (for checkpoints and notes)."""
    return separation if isinstance(separation, str) else ",".join(name for name, _ in separation)


def placed_layers(layers, placement):
    """``layers`` with every ink's density scaled where ``placement`` (a function of the inks' density together,
    their sum) lowers it: all the inks' dots are placed as one stipple of that density, each ink keeping its
    share at every pixel (a pen's dots clipped at its reach, ``stipple.pipelines.pen.placement_density``)."""
    scale = placement_scale(sum(layer.density for layer in layers), placement)
    return layers if scale is None else [replace(layer, density=layer.density * scale) for layer in layers]


def placement_scale(union, placement):
    """``placement(union) / union`` per pixel (1 where the union is empty), or None where ``placement`` leaves
    the union as it is: the factor that scales every ink's density by the same share (``placed_layers``)."""
    placed = placement(union)
    if placed is union:
        return None
    return np.divide(placed, union, out=np.ones_like(union), where=union > 0)


def colour_problem(
    rgb, n_points, bandwidth=None, *, separation="cmyk", black=1.0, union_weight=1.0, placement=None, **options
):
    """The joint halftoning problem of an RGB image's inks: ``(layers, problem)``.

    Parameters
    ----------
    rgb : numpy.ndarray or path
        ``(H, W, 3)`` colours in [0, 1], or an image file (``stipple.io.images.load_colour``).
    n_points : int
        Dots in all; each ink gets its share by mass (``stipple.multiclass.class_counts``).
    bandwidth : int, optional
        The union's bandwidth (see ``stipple.multiclass.multiclass_problem``).
    separation, black :
        See ``separate``.
    union_weight : float
        Factor of the union's term against the inks' (1: Wei's and Schmaltz et al.'s equal weights; 0: each
        ink alone, so dots of different inks may clump). A single ink has no union term.
    placement : callable, optional
        The density to place all the dots by, as a function of the inks' together (``placed_layers``); the
        returned layers carry the scaled densities.
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
    if placement is not None:
        layers = placed_layers(layers, placement)
    check_union_weight(union_weight)
    term_weights = [1.0] * len(layers) + [float(union_weight) if len(layers) > 1 else 0.0]
    problem = multiclass_problem(
        [layer.density for layer in layers],
        n_points,
        bandwidth,
        names=[layer.name for layer in layers],
        term_weights=term_weights,
        **options,
    )
    problem.settings.update(separation=palette_label(separation), black=float(black))
    return [layer for layer in layers if layer.name in problem.names], problem


def halftone_colour(rgb, n_points, bandwidth=None, *, separation="cmyk", black=1.0, union_weight=1.0, **options):
    """Stipple an RGB image with one class of dots per ink: ``(layers, problem, result)``.

    Ink ``c``'s dots are ``result.points[problem.slices[c]]`` (unit coordinates, x right, y down). ``options``
    are ``colour_problem``'s and ``stipple.halftone.run``'s (``init``, ``seed``, ``tol``, ``iterations``, ...).
    """
    problem_keys = ("backend", "threads", "epsilon", "hessian", "near_field", "placement")
    problem_options = {key: options.pop(key) for key in problem_keys if key in options}
    layers, problem = colour_problem(
        rgb, n_points, bandwidth, separation=separation, black=black, union_weight=union_weight, **problem_options
    )
    return layers, problem, run(problem, **options)
