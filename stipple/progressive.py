"""Plots that may stop at any moment: dots in passes whose every prefix is an even stipple of the whole image.

The dots are one array in passes ``P_1, ..., P_L`` (``LEVELS`` by default); level ``k`` is the prefix
``P_1 ∪ ... ∪ P_k`` with ``m_k`` dots. The objective is the multi-class one (``stipple.multiclass``) with the
levels as its terms:

    E(p) = sum_k a_k E(p[:m_k]; w),

each level's own discrepancy (with its own default bandwidth and near field) against the same density, so every
prefix is a stipple of the whole image at its own density. The factors ``a_k`` are ``level_factors``: the
levels the order promises are the doublings, ``M / 2^j`` dots (with four passes the quarter, the half and the
whole), and two levels of which one has twice the dots of the other pull against each other. A good stipple is
locally close to a triangular lattice; a triangular lattice has triangular sublattices of index 3 and 4 but none
of index 2, so the quarter and the whole can both be nearly hexagonal but the half, between them, cannot be as
well. Weighted by their shares of the dots alone (``a_k = m_k / M``, i.e. each level's ``E_N`` over its i.i.d.
expectation counted alike), the half lost to both its neighbours: ``E_N`` 1.05 / 1.17 / 1.25 / 1.11 times that
of independent stipples at 25 / 50 / 75 / 100 %, and its picture up to 1.6 times the RMSE (docs/plotters.md).
So a promised level counts its share once for each promised level it doubles or halves: the half, squeezed from
both sides, twice; the levels between the doublings (75 %) a third of their share, to remain even stipples
without pulling the half apart (at two thirds of their share the half's picture went back above 1.3 times the
RMSE). With four passes: 0.25, 1, 0.25, 1.

The start is the stratified one (dots shared out along a Hilbert curve) dealt into passes in bit-reversed turns
(for 4 passes: dots 0, 4, 8, ... first, then 2, 6, 10, ...), so every level starts spread over the image. The
low-frequency correction (``stipple.halftone``) runs on the full set, as for one stipple: its smooth deformation
moves every level alike. On paper each pass is drawn along its own short pen path
(``stipple.render.pen.plotter_order``), the passes one after another. Several inks (``progressive_inks``,
through the vpype plug-in) are the joint problem of ``stipple.colour`` with every ink's term replaced by its
own levels' terms: each pen's layer is drawn in its own passes, and the union's term keeps the inks apart.
"""

from dataclasses import replace

import numpy as np

from .multiclass import TERM_SETTINGS, MulticlassObjective, MulticlassProblem, term_problem
from .render.pen import path_length, plotter_order
from .torus import DEFAULT_EPSILON, torus_problem

LEVELS = 4
# A level between the doublings counts this fraction of its share of the dots (see the module docstring).
BETWEEN_SHARE = 1 / 3


def pass_offsets(levels):
    """The order in which ``levels`` interleaved passes are dealt: bit-reversed (van der Corput) turns."""
    bits = max(int(np.ceil(np.log2(levels))), 0)
    keys = [int(format(offset, f"0{bits}b")[::-1], 2) if bits else 0 for offset in range(2**bits)]
    return [offset for _, offset in sorted(zip(keys, range(2**bits), strict=True)) if offset < levels]


def pass_counts(n_points, levels=LEVELS):
    """Dots per pass, in pass order: the passes of ``interleave``."""
    return [len(range(offset, n_points, levels)) for offset in pass_offsets(levels)]


def promised_levels(levels):
    """The levels ``k`` (1-based, of ``levels`` passes) that are doublings: ``levels / k`` a power of two."""
    return [k for k in range(1, levels + 1) if levels % k == 0 and (levels // k) & (levels // k - 1) == 0]


def level_factors(ends):
    """The factors ``a_k`` of the levels with ``ends[k-1]`` dots (the last one the full set's).

    A promised level (``promised_levels``) gets its share ``m_k / M`` once for each promised level with twice or
    half its dots (at least once); a level between them ``BETWEEN_SHARE`` of its share.
    """
    ends = np.asarray(ends, dtype=np.float64)
    promised = set(promised_levels(len(ends)))
    factors = []
    for k, share in enumerate(ends / ends[-1], start=1):
        if k in promised:
            doubled = sum(other in promised for other in (k // 2 if k % 2 == 0 else 0, 2 * k))
            factors.append(float(share * max(doubled, 1)))
        else:
            factors.append(float(share * BETWEEN_SHARE))
    return factors


def interleave(points, levels=LEVELS):
    """``points`` (in an order along which they are spread, e.g. a Hilbert curve) dealt into passes."""
    return np.concatenate([points[offset::levels] for offset in pass_offsets(levels)])


def progressive_problem(
    weights,
    n_points,
    bandwidth=None,
    *,
    levels=LEVELS,
    backend="ducc0",
    threads=None,
    epsilon=DEFAULT_EPSILON,
    hessian="gauss-newton",
    near_field=True,
):
    """The torus problem of ``weights`` with ``n_points`` dots whose every level is its own term.

    Parameters
    ----------
    weights : numpy.ndarray
        The density ``w`` (H, W).
    n_points : int
        Total number of dots M.
    bandwidth : int, optional
        The full set's bandwidth (default ``default_bandwidth``); level ``k`` gets its own default, or
        ``N sqrt(m_k / M)`` when ``bandwidth`` is given.
    levels : int
        Number of passes L (at least 1, at most M).
    backend, threads, epsilon, hessian, near_field :
        As for ``stipple.torus.torus_problem``, for every level.

    Returns
    -------
    stipple.multiclass.MulticlassProblem
        ``slices`` are the levels (prefixes), ``classes`` their problems, the last one the full set's.
    """
    from .errors import StippleError

    if not isinstance(levels, (int, np.integer)) or levels < 1:
        raise StippleError(f"the progressive order's passes must be a positive integer, not {levels!r}")
    if levels > n_points:
        raise StippleError(
            f"--order progressive draws {levels} passes, so it needs at least {levels} dots, not -M {n_points}"
        )
    options = {"backend": backend, "threads": threads, "epsilon": epsilon, "hessian": hessian, "near_field": near_field}
    full = torus_problem(weights, n_points, bandwidth, **options, **TERM_SETTINGS)
    ends = np.cumsum(pass_counts(n_points, levels))
    parts = [term_problem(weights, end, n_points, bandwidth, options) for end in ends[:-1]] + [full]
    slices = [slice(0, int(end)) for end in ends]
    factors = level_factors(ends)
    objective = MulticlassObjective([part.objective for part in parts], slices, factors)
    return MulticlassProblem(
        domain="torus",
        manifold=full.manifold,
        objective=objective,
        discrepancy=full.discrepancy,
        n_points=full.n_points,
        bandwidth=full.bandwidth,
        sample=full.sample,
        stratified=lambda rng, count: interleave(full.stratified(rng, count), levels),
        settle=full.settle,
        coarse=full.coarse,
        settings={
            **full.settings,
            "order": "progressive",
            "level_points": [int(end) for end in ends],
            "level_bandwidths": [part.bandwidth for part in parts],
            "term_weights": factors,
        },
        names=[f"level{index}" for index in range(1, levels + 1)],
        classes=parts,
        slices=slices,
    )


def progressive_order(centres, counts):
    """A visiting order that draws the passes (``counts`` dots each, in array order) one after another, each
    along its own short pen path; and the pen-up travel of the array order and of the new one."""
    ends = np.cumsum(counts)
    order = np.concatenate(
        [start + plotter_order(centres[start:end])[0] for start, end in zip(ends - counts, ends, strict=True)]
    )
    return order, path_length(centres), path_length(centres[order])


def progressive_inks(layers, problem, *, levels=LEVELS, **options):
    """The joint problem of several inks (``stipple.colour.colour_problem``'s ``problem``) with each ink's dots
    in nested levels: every ink's class term becomes its own levels' terms (``progressive_problem``), the
    union's term (all inks' dots, the last one) stays.

    Parameters
    ----------
    layers : sequence of stipple.colour.Layer
        The inks that got dots, in the order of ``problem.slices``.
    problem : stipple.multiclass.MulticlassProblem
    levels : int
        Passes per ink (an ink with fewer dots gets one pass per dot).
    options :
        ``progressive_problem``'s ``backend``, ``threads``, ``epsilon``, ``hessian``, ``near_field``.

    Returns
    -------
    tuple
        The ``MulticlassProblem`` and each ink's dots per pass, in array order.
    """
    inks = [
        progressive_problem(
            layer.density, part.stop - part.start, levels=min(levels, part.stop - part.start), **options
        )
        for layer, part in zip(layers, problem.slices, strict=True)
    ]
    terms, slices, factors = [], [], []
    for ink, part in zip(inks, problem.slices, strict=True):
        terms += ink.objective.terms
        factors += ink.objective.weights
        slices += [slice(part.start + level.start, part.start + level.stop) for level in ink.slices]
    union = problem.objective
    objective = MulticlassObjective([*terms, union.terms[-1]], [*slices, slice(None)], [*factors, union.weights[-1]])
    nested = replace(
        problem,
        objective=objective,
        stratified=lambda rng, count: np.concatenate([ink.stratified(rng, ink.n_points) for ink in inks]),
        settle=inks[0].settle,
        settings={
            **problem.settings,
            "order": "progressive",
            "ink_level_points": [ink.settings["level_points"] for ink in inks],
        },
    )
    return nested, [np.asarray(pass_counts(ink.n_points, len(ink.slices))) for ink in inks]


def progressive_colour(rgb, n_points, *, separation="gray", black=1.0, union_weight=1.0, placement=None, **options):
    """``stipple.colour.halftone_colour`` with each ink's dots in nested levels: ``(layers, result, counts)``.

    One ink is ``progressive_problem``'s (no union term); several are ``progressive_inks``'s, the union's term
    weighted ``union_weight``. ``placement``: as for ``stipple.colour.colour_problem``. ``options`` are
    ``progressive_problem``'s and ``stipple.halftone.run``'s. ``counts`` are each ink's dots per pass, in array
    order (the inks one after another, as ``layers``).
    """
    from .colour import colour_problem, placed_layers, separate
    from .halftone import run
    from .io.images import load_colour

    rgb = rgb if isinstance(rgb, np.ndarray) else load_colour(rgb)
    keys = ("backend", "threads", "epsilon", "hessian", "near_field", "levels")
    settings = {key: options.pop(key) for key in keys if key in options}
    layers = separate(rgb, separation, black)
    if len(layers) == 1:
        layers = layers if placement is None else placed_layers(layers, placement)
        problem = progressive_problem(layers[0].density, n_points, **settings)
        return layers, run(problem, **options), [np.asarray(pass_counts(n_points, len(problem.slices)))]
    levels = settings.pop("levels", LEVELS)
    layers, joint = colour_problem(
        rgb, n_points, separation=separation, black=black, union_weight=union_weight, placement=placement, **settings
    )
    problem, counts = progressive_inks(layers, joint, levels=levels, **settings)
    return layers, run(problem, **options), counts


def order_dots(dots, order=None, counts=None):
    """``stipple.render.drawing.Dots`` in plotting order: unchanged (None), along one short path ("path"), or pass by
    pass (``"progressive"``, ``counts`` dots per pass)."""
    if order is None or len(dots.centres) < 2:
        return dots
    if order == "progressive":
        visit = progressive_order(dots.centres, counts)[0]
    else:
        visit = plotter_order(dots.centres)[0]
    dots.centres, dots.radii = dots.centres[visit], dots.radii[visit]
    return dots
