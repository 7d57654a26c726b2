"""One-line drawings: a closed polygon whose arclength measure minimises the discrepancy to an image.

The curve-based approximation of Ehler, Gräf, Neumayer and Steidl (Found. Comput. Math. 2021): vertices
``p_1..p_M`` of a closed polygon, equally spaced along it, carry the equal-weight quadrature ``lam sum_i f(p_i)``
of the curve's length measure, and minimise the same ``E_N`` (transforms, ball kernel, near field, CG) as the dots
of ``stipple torus``. The speed constraint ``|p_{i+1} - p_i| = h = L/M`` is a quadratic penalty, an object
composed with ``SumObjective``; ``draw_line`` drives its weight up in phases until every segment is within
``constraint_tol`` (1 %) of ``h``. The curve lives in the image's rectangle (``Rectangle``: steps are clipped to
it, not wrapped), so the drawing never crosses the torus seam; the transforms stay periodic.

The discrepancy and the near field are taken at ``K`` quadrature nodes per segment (``CurveNodes``: the
trapezoidal rule of the length measure), so that the drawn ink, not only the vertices, is even. The near field
leaves out pairs of nodes up to ``exclude`` nodes apart along the curve (the near-field radius over the node
spacing, plus one): they are meant to be close and their repulsion would only stretch the curve.
"""

from dataclasses import dataclass

import numpy as np

from ..checks import check_integer
from ..errors import StippleError
from ..halftone import MAX_BANDWIDTH, Problem, check_count
from ..manifolds import Rectangle
from ..nearfield import NearField, TorusPairs
from ..objective import SumObjective
from ..peaks import darkest_level
from ..torus import check_weights, torus_problem
from ..torus_spectrum import torus_near_kernel, torus_scale
from .start import MIN_CURVE_VERTICES, initial_loop
from .terms import CurveNodes, SpeedConstraint, curve_neighbours

# Default length: L = c sqrt(M W H) pixels, c = LENGTH_FACTOR (rho / REFERENCE_DENSITY)**-LENGTH_EXPONENT with
# rho = M / (W H) vertices per pixel, clipped to LENGTH_FACTOR_RANGE. Measured on the tuning images (portrait and
# camera, 256 px, PSNR at sigma 2 px; /tmp scans summarised in docs/line.md): best c = 0.75-0.9 at rho = 0.31
# (M = 20000), 0.9-1.05 at rho = 0.15, 1.0-1.25 at rho = 0.046. A sparse line needs to be relatively longer or its
# strokes (W H / L apart) show at sigma = 2 px; a dense one must stay short or it overlaps itself where the image is
# dark (strokes drawn 1 px wide closer than a pixel).
LENGTH_FACTOR = 0.75
REFERENCE_DENSITY = 0.305
LENGTH_EXPONENT = 0.15
LENGTH_FACTOR_RANGE = (0.6, 1.1)
# ... and at most FILL_COVERAGE times the length that covers the darkest tone once with a 1-px pen. It binds on
# silhouettes: on a tuning figure (19 % dark) at M = 10000 the uncapped 19304 px gave 37.8/41.5 dB (sigma 2/4 px),
# strokes overlapping nearly twice over; capped, 11943 px gave 41.2/46.3 (TSP art 40.0/45.5).
FILL_COVERAGE = 1.1
MIN_STEP_SPACINGS = 0.5
DARKEST_MASS_SHARE = 0.01
# Default bandwidth: N = 4.02 / (stroke spacing where the image is darkest), the dots' ratio with the stroke
# spacing as the spacing. With the mean spacing instead, the objective could not tell strokes stacked in pairs from
# strokes a pixel apart in a dark region: from the LKH tour on the tuning figure, 100-400 iterations lowered PSNR
# from 40.1 to 31-34 dB; with 3x the bandwidth they raised it to 42.7. The ratio t / mean w (t = darkest_tone) is
# 1.1-2 on photos, 3-5.2 on the silhouettes measured; beyond MAX_PEAK_RATIO (a lone dark spot) it would only slow
# the transforms.
MAX_PEAK_RATIO = 6.0
MODES_PER_SPACING = 4.02
# Quadrature nodes along each segment (``CurveNodes``), at most this many pixels apart: the drawn line is ink
# along its segments, not at its vertices, and segments longer than a pixel let the vertices look even while the
# ink does not. Measured on the tuning images (PSNR at sigma 2/4 px, K = 1 -> 2 -> 4 nodes per segment): portrait
# M = 3000 (h = 4.6 px) 17.5/28.8 -> 18.8/29.6 -> 19.1/29.9 dB, camera 17.7/28.6 -> 19.0/29.7 -> 19.2/29.8, shapes
# 25.8/33.1 -> 27.9/34.3 -> 28.2/34.5; portrait M = 10000 (h = 2.1 px) K = 1, 2, 3: 24.7/33.1, 25.3/34.5,
# 25.4/35.0; M = 20000 (h = 1.4 px) K = 1, 2: 28.0/33.5, 28.7/35.1. Time grows with the nodes: 30000 vertices on
# the 512² portrait (h = 2.6 px) took 32, 51 and 65 s with K = 1, 2, 3 (22.8/31.8, 23.5/32.8, 23.6/33.1 dB).
NODE_SPACING = 1.0
MAX_SUBDIVISIONS = 4
PENALTY_GROWTH = 8.0
# The first phase's penalty weight (times ``penalty_scale``). Measured on the portrait (M = 20000, 40 iterations
# from the same start): with 1e-3 (the previous value) the penalty's energy was 100x the discrepancy's, CG spent
# itself on segment lengths, E_N + near field ended at 6.0e-6 and the curve drifted off one edge of the image;
# with 1e-7 it ended at 3.8e-9 (the discrepancy alone: 3.1e-9). Later phases raise it until the speed holds.
INITIAL_PENALTY = 1e-7
# Iterations of the first phase; each later phase runs a quarter as many.
LINE_ITERATIONS = 400
MAX_PHASES = 8
# White margin around the image on the line's torus, in mean stroke spacings (see ``Rectangle``); measured on the
# portrait, 2 pixels, 4 and 12 spacings gave the same PSNR within 0.2 dB.
MARGIN_SPACINGS = 2.0


@dataclass
class LineProblem(Problem):
    """A ``Problem`` whose points are the vertices of one closed curve, in path order.

    ``speed`` is the speed penalty (``stipple.line.terms.SpeedConstraint``) and ``step`` the segment length
    ``h = L / M`` it holds the segments to (unit lengths of the padded torus), ``length`` the curve's length ``L``
    in pixels and ``pixels_per_unit`` the padded image's longer side, in pixels.
    """

    speed: object = None
    step: float = 0.0
    length: float = 0.0
    pixels_per_unit: int = 0


def default_length(n_vertices, weights):
    """Default curve length in pixels: ``c sqrt(M W H)`` with ``c`` from the vertex density (see ``length_factor``),
    at most ``FILL_COVERAGE`` times the length that covers the darkest tone once, ``A = sum w / t`` (1-px pen;
    ``t = darkest_tone(weights)``), but not below ``MIN_STEP_SPACINGS sqrt(M A)``: steps of at least half the
    spacing of M dots on ``A`` (a small dark spot would otherwise get a line of a few pixels).

    A TSP tour through M dots is ~0.7 sqrt(M W H) on a flat image; through the portrait's 20000 default dots LKH
    found 34930 px = 0.96 sqrt(M W H).
    """
    rows, columns = weights.shape
    length = length_factor(n_vertices / (rows * columns)) * float(np.sqrt(n_vertices * rows * columns))
    dark_area = float(weights.sum()) / darkest_tone(weights)
    return min(length, max(FILL_COVERAGE * dark_area, MIN_STEP_SPACINGS * np.sqrt(n_vertices * dark_area)))


def length_factor(density):
    """Length factor ``c`` for ``density`` vertices per pixel: 0.75 at 0.305, growing as the line gets sparser."""
    factor = LENGTH_FACTOR * (density / REFERENCE_DENSITY) ** -LENGTH_EXPONENT
    return float(np.clip(factor, *LENGTH_FACTOR_RANGE))


def default_subdivisions(length, n_vertices):
    """Quadrature nodes per segment: ``ceil(h / NODE_SPACING)`` for segments ``h = L / M`` pixels long, at most
    ``MAX_SUBDIVISIONS``."""
    return int(np.clip(np.ceil(length / n_vertices / NODE_SPACING - 1e-9), 1, MAX_SUBDIVISIONS))


def darkest_tone(weights):
    """The density that the darkest ``DARKEST_MASS_SHARE`` of the ink reaches: the largest ``t`` with at least that
    share of ``sum w`` in pixels of ``w >= t`` (robust to a few outlying pixels, unlike ``max w``;
    ``stipple.peaks.darkest_level``)."""
    return darkest_level(weights, mass_fraction=DARKEST_MASS_SHARE)[0]


def default_line_bandwidth(length, weights):
    """Even ``N = 4.02 / s`` along the longer side, ``s = (W H / L) (mean w / t)`` the stroke spacing where the
    image is darkest, ``t = darkest_tone(weights)`` (unit lengths): the line's ink per area follows ``w``, so its
    spacing goes as ``1 / w``. The ratio ``t / mean w`` counts up to ``MAX_PEAK_RATIO``, N up to ``MAX_BANDWIDTH``."""
    rows, columns = weights.shape
    peak = min(darkest_tone(weights) / float(weights.mean()), MAX_PEAK_RATIO)
    spacing = rows * columns / length / max(rows, columns) / peak
    return min(int(2 * np.ceil(MODES_PER_SPACING / spacing / 2)), MAX_BANDWIDTH)


def line_settings(weights, n_vertices, length=None, bandwidth=None, names=None):
    """``(length, bandwidth)`` of a line, given or by default, checked so that the padded torus's grid stays
    bounded: ``length`` in ``length_bounds`` (the blank margin at most ``MAX_MARGIN_SIDES`` times the image's
    longer side), ``bandwidth`` even in [2, ``bandwidth_limit``] (the padded bandwidth at most ``MAX_BANDWIDTH``).
    ``names`` spell the two settings in messages (the command line's options; default "length", "bandwidth")."""
    weights = check_weights(weights)
    names = {"length": "length", "bandwidth": "bandwidth", **(names or {})}
    low, high = length_bounds(weights.shape)
    if length is None:
        length = float(np.clip(default_length(n_vertices, weights), low, high))
    elif not (isinstance(length, (int, float, np.number)) and np.isfinite(length) and low <= length <= high):
        rows, columns = weights.shape
        raise StippleError(
            f"{names['length']} must be in [{low:.4g}, {high:.4g}] pixels for a {columns}×{rows} image (shorter, the "
            f"blank margin would be over {MAX_MARGIN_SIDES} times the image; longer, strokes under "
            f"1/{MAX_LENGTH_COVERAGE} px apart), not {length!r}"
        )
    limit = bandwidth_limit(length, weights.shape)
    if bandwidth is None:
        return float(length), min(default_line_bandwidth(length, weights), limit)
    bandwidth = check_integer(names["bandwidth"], bandwidth, 2, limit, even=True)
    return float(length), bandwidth


# The blank margin around the image is at most this many times the image's longer side (a shorter --length is
# refused: it would grow the padded grid without bound); a line at most MAX_LENGTH_COVERAGE times the image's area
# (strokes 1/16 px apart).
MAX_MARGIN_SIDES, MAX_LENGTH_COVERAGE = 4, 16


def length_bounds(shape):
    """The least and the largest curve length in pixels of a ``shape`` image (see ``line_settings``)."""
    rows, columns = shape
    return MARGIN_SPACINGS * rows * columns / (
        MAX_MARGIN_SIDES * max(rows, columns)
    ), MAX_LENGTH_COVERAGE * rows * columns


def bandwidth_limit(length, shape):
    """The largest even bandwidth whose padded bandwidth (the margin adds modes) stays at most ``MAX_BANDWIDTH``."""
    longest = max(shape) + 2 * blank_margin(length, shape)
    return max(2, int(MAX_BANDWIDTH * max(shape) / longest) // 2 * 2)


def blank_margin(length, shape):
    """Pixels of white margin around the image: ``MARGIN_SPACINGS`` mean stroke spacings ``W H / L``, at least 2."""
    rows, columns = shape
    return max(2, int(np.ceil(MARGIN_SPACINGS * rows * columns / length)))


def line_problem(
    weights,
    n_vertices,
    length=None,
    bandwidth=None,
    *,
    penalty=1.0,
    threads=None,
    epsilon=1e-9,
    backend="ducc0",
    hessian="gauss-newton",
    subdivisions=None,
):
    """The one-line problem: discrepancy of the curve measure, curve near field, speed penalty.

    Parameters
    ----------
    weights : array_like of shape (H, W)
        Density ``w >= 0`` (dark = ink).
    n_vertices : int
        Vertices M of the closed polygon (at least 4).
    length : float, optional
        Largest curve length L in pixels (default ``default_length``).
    bandwidth : int, optional
        Even bandwidth N along the image's longer side (default ``default_line_bandwidth``); the torus, which
        adds a blank margin, gets as many more modes as keep the resolution.
    penalty : float
        Weight of the speed penalty relative to ``penalty_scale`` (``draw_line`` raises it in phases).
    threads, epsilon, backend : see ``stipple.torus.torus_problem``.
    hessian : {"gauss-newton", "full"}
        "full" makes every term's Hessian exact (for tests); the default keeps CG's curvature positive.
    subdivisions : int, optional
        Quadrature nodes per segment ``K`` (``CurveNodes``; default ``default_subdivisions``).

    Returns
    -------
    LineProblem
        ``objective = SumObjective(CurveNodes(discrepancy), CurveNodes(near field), speed)``;
        ``settings['domain'] == 'line'``.

    The discrepancy is the dots' (``stipple.torus.torus_problem`` of the padded image with ``M K`` nodes: the
    same checks, coefficients, kernel and settings); the near field is the curve's own, which leaves out
    neighbours along the curve.
    """
    weights = check_weights(weights)
    n_vertices = check_count(n_vertices)
    if n_vertices < MIN_CURVE_VERTICES:
        raise StippleError(f"a closed curve needs at least {MIN_CURVE_VERTICES} vertices, not {n_vertices}")
    length, bandwidth = line_settings(weights, n_vertices, length, bandwidth)
    margin = blank_margin(length, weights.shape)
    padded = np.pad(weights, margin)
    longest = max(padded.shape)
    padded_bandwidth = int(2 * np.ceil(bandwidth * longest / max(weights.shape) / 2))
    subdivisions = (
        default_subdivisions(length, n_vertices)
        if subdivisions is None
        else check_integer("subdivisions", subdivisions, 1, 64)
    )
    nodes = n_vertices * subdivisions
    dots = torus_problem(
        padded, nodes, padded_bandwidth, backend=backend, threads=threads, epsilon=epsilon, hessian=hessian
    )
    scale = torus_scale(padded.shape)
    step = length / longest / n_vertices
    near_kernel = torus_near_kernel(dots.bandwidth, scale)
    steps = int(np.ceil(near_kernel.radius * subdivisions / step)) + 1
    discrepancy = dots.discrepancy
    # The curve's near field takes the threads of the dots' (``stipple.torus.pair_share``), at once with the
    # transforms where those have their own.
    dots_pairs = dots.objective.terms[-1]
    near = NearField(
        near_kernel,
        discrepancy.weight,
        TorusPairs(scale),
        factor=float(np.prod(scale)),
        hessian=hessian,
        exclude=curve_neighbours(nodes, steps),
        threads=dots_pairs.threads,
    )
    mu = penalty * penalty_scale(discrepancy.weight * subdivisions, n_vertices)
    speed = SpeedConstraint(step, mu, scale, hessian)
    rows, columns = padded.shape
    rectangle = Rectangle(scale, low=(margin / columns, margin / rows), high=(1 - margin / columns, 1 - margin / rows))
    settings = {
        **dots.settings,
        "domain": "line",
        "length": length,
        "penalty": float(penalty),
        "exclude": steps,
        "subdivisions": subdivisions,
        "margin": margin,
    }
    return LineProblem(
        domain="torus",
        manifold=rectangle,
        objective=SumObjective(
            CurveNodes(discrepancy, subdivisions),
            CurveNodes(near, subdivisions),
            speed,
            concurrent=dots.objective.concurrent,
        ),
        discrepancy=discrepancy,
        n_points=n_vertices,
        bandwidth=dots.bandwidth,
        sample=lambda rng, count: rectangle.inward(initial_loop(weights, count, int(rng.integers(2**31)), threads)),
        settings=settings,
        speed=speed,
        step=step,
        length=length,
        pixels_per_unit=longest,
    )


def penalty_scale(vertex_weight, n_vertices):
    """The unit of the penalty weight: ``lam² M``, with ``lam = m / M`` the weight of a vertex (``m`` the mass).

    The estimate behind it (a 1 % stretch costs as much force as one vertex's discrepancy) overstates the force:
    measured, the penalty balances the discrepancy near ``1e-7`` of this unit (``INITIAL_PENALTY``).
    """
    return float(vertex_weight**2 * n_vertices)
