"""Dots as discs: positions and sizes optimised together by the same CG (issue #23, point 3).

In the paper's framework a dot is a quadrature node with a weight; a drawn dot is a disc whose area is that
weight. Here the drawn ink is the measure ``mu = sum_i 1_{D(p_i, r_i)}`` (disc of radius ``r_i`` around ``p_i``,
physical units: the torus is ``[0, W/L) x [0, H/L)``, ``L = max(W, H)``, so the longer side has length 1).
The model is LINEAR: where discs overlap their ink is counted twice (paper under two discs is covered once, so
dark regions whose discs overlap come out lighter than the model says). The target is the image's ink density
``w`` (the darkness, ``load_density``), whose integral, ``mean(w)`` times the canvas area ``A = W H / L^2``, is
the ink the discs must lay down.

Coefficients, in stipple's unit coordinates (``w_n = int_{[0,1)^2} w(u) e^{-2 pi i n.u} du``, physical frequency
``xi = (n1 L/W, n2 L/H)``)::

    mu_n = (1/A) sum_i a_i phi(|xi_n| r_i) e^{-2 pi i n.p_i},   a_i = pi r_i^2,   phi(rho) = 2 J1(2 pi rho)/(2 pi rho)
    E(p, s) = sum_n K_n |mu_n - w_n|^2

with stipple's ball-discrepancy kernel ``K_n = kB(|xi_n|)`` at the default bandwidth and, unlike the point
problem, ``K_0 = kB(0) = pi^2/160`` (``mass_weight``): with free sizes nothing else fixes the total ink (on a
constant image every common disc area would give the same energy). The size variable is ``s_i = log a_i``: sizes
stay positive, and ``d(a phi)/ds = a J0(2 pi |xi| r)`` carries the same factor ``a_i`` as the position
derivative, so one constant metric weight on ``s`` balances the two for every dot (``size_metric``).

``a phi(|xi| r)`` depends on the dot and the mode, so it is made a few NUFFTs by a separable approximation
``pi u phi(|xi| sqrt(u)) = sum_q beta_q(|xi|) alpha_q(u)``, ``u = r^2`` (``stipple.disc_measure.DiscFactors``):
Chebyshev interpolation in ``u`` on ``[0, U]`` compressed by an SVD over ``|xi|`` in the band, to ``epsilon``
relative to the largest disc's area. Rank 7 to 10 for ``|xi|_max r_max`` from 1 to 2 at 1e-7; the Taylor series
in ``r^2`` needs 15 to 25 terms there and, its terms alternating, amplifies each transform's error by
``I1(2x)/x``, ``x = pi |xi| r`` (40 at 1.1, 15,000 at 2.2). Then, with ``T1``/``T2`` stipple's type-1/type-2 NUFFTs::

    mu_n        = (1/A) sum_q beta_q(n) T1[alpha_q(u_i)]_n                                 (ceil(R/2) transforms)
    dE/dp_i     = (2/A) Re sum_q alpha_q(u_i) T2[(2 pi i n) beta_q K R]_i                (R, x and y packed)
    dE/ds_i     = (2/A) sum_q u_i alpha_q'(u_i) Re T2[beta_q K R]_i                      (ceil(R/2))
    (J v)_n     = (1/A) sum_q beta_q(n) ( -2 pi i n . T1[alpha_q v_p]_n + T1[u alpha_q' v_s]_n )

``R = mu - w``; Gauss-Newton form ``v . H v' = 2 Re sum_n K_n conj(J v)_n (J v')_n``. Real data are packed two to
a complex transform. The objective is what ``stipple.optimize.minimize`` drives, on ``DiscTorus``.
"""

import os
import time
from dataclasses import dataclass

import numpy as np

from ..checks import MAX_ITERATIONS
from ..errors import StippleError
from ..halftone import (
    check_bandwidth,
    check_count,
    check_epsilon,
    check_integer,
    check_memory,
    check_threads,
    default_threads,
)
from ..io.images import load_density
from ..kernels import ball_kernel
from ..nufft import BACKENDS, make_nufft
from ..optimize import BETAS, minimize
from ..sampling import stratified_sample
from ..torus import DEFAULT_EPSILON, check_weights, default_bandwidth
from ..torus_spectrum import axis_bandwidths, image_coefficients, torus_kernel, torus_scale
from .measure import (
    DiscDiscrepancy,
    DiscFactors,
    DiscTorus,
    balanced_size_metric,
    disc_factor,
    disc_transform,
)

__all__ = [
    "DiscDiscrepancy",
    "DiscFactors",
    "DiscProblem",
    "DiscResult",
    "DiscTorus",
    "balanced_size_metric",
    "disc_factor",
    "disc_problem",
    "disc_transform",
    "optimise_discs",
    "tone_radius",
]

# Default stop: the relative gradient norm, the iterations and the settle fraction of ``stipple.optimize``.
DEFAULT_TOL = 1e-3
DEFAULT_ITERATIONS = 200
DEFAULT_SETTLE = 0.0


def tone_radius(weights, n_points):
    """The radius at which ``n_points`` equal discs lay down the image's ink ``mean(w) A``, physical units."""
    weights = np.asarray(weights, dtype=float)
    return float(np.sqrt(np.prod(torus_scale(weights.shape)) * weights.mean() / (np.pi * n_points)))


@dataclass
class DiscProblem:
    """The disc-measure problem of one image and dot count: objective, manifold and their settings."""

    objective: DiscDiscrepancy
    manifold: DiscTorus
    bandwidth: int
    scale: np.ndarray
    tone_radius: float
    mass_weight: float

    def pack(self, points, radii):
        """``(M, 3)`` array ``(x, y, log(pi r^2))`` from unit-coordinate positions and physical radii (or one)."""
        radii = np.broadcast_to(np.asarray(radii, dtype=float), (len(points),))
        return np.column_stack([points, np.log(np.pi * radii**2)])

    def energy(self, points, radii):
        """``E`` of discs of ``radii`` at ``points``."""
        self.objective.set_points(self.pack(points, radii))
        return self.objective.energy()


def disc_problem(
    weights,
    n_points,
    bandwidth=None,
    *,
    backend="ducc0",
    threads=None,
    epsilon=DEFAULT_EPSILON,
    mass_weight=None,
    radius=None,
):
    """The disc-measure problem of ``weights`` (an (H, W) ink density or an image file) with ``n_points`` discs.

    Parameters
    ----------
    weights : array_like or path
        Ink density ``w >= 0`` (darkness, 1 = black), rows top to bottom, or a file for ``load_density``.
    n_points : int
        Number of discs M, 1 <= M <= 20,000,000.
    bandwidth : int, optional
        Even bandwidth N along the longer side (default ``stipple.torus.default_bandwidth(M, weights)``).
    backend : {"ducc0", "finufft", "cufinufft"}
    threads : int, optional
        Threads of the transforms (default: all CPUs).
    epsilon : float
        Accuracy of the transforms and of the disc factors, in [1e-14, 1e-2].
    mass_weight : float, optional
        ``K_0``, the weight of the total-ink mismatch, >= 0 (default ``kB(0) = pi^2 / 160``).
    radius : float, optional
        Radius at which ``size_metric`` balances sizes against positions (default: the tone radius).
    """
    weights = check_weights(load_density(weights) if isinstance(weights, (str, os.PathLike)) else weights)
    n_points = check_count(n_points)
    bandwidth = check_bandwidth(default_bandwidth(n_points, weights) if bandwidth is None else bandwidth)
    if backend not in BACKENDS:
        raise StippleError(f"backend must be one of {', '.join(BACKENDS)}, not {backend!r}")
    threads = default_threads() if threads is None else check_threads(threads)
    epsilon = check_epsilon(epsilon)
    mass_weight = float(ball_kernel(0.0)) if mass_weight is None else mass_weight
    if not isinstance(mass_weight, (int, float, np.floating)) or not 0 <= mass_weight < np.inf:
        raise StippleError(f"mass_weight must be a finite number >= 0, not {mass_weight!r}")
    scale = torus_scale(weights.shape)
    bandwidths = axis_bandwidths(bandwidth, weights.shape)
    # About 100 complex mode grids at rank ~12 (factors, packed batches of both transforms), 100 values a dot.
    check_memory(
        100 * 16 * (bandwidths[0] + 1) * (bandwidths[1] + 1) + 100 * 8 * n_points, f"M={n_points}, N={bandwidth}"
    )
    kernel = torus_kernel(bandwidths, scale)
    kernel[bandwidths[0] // 2, bandwidths[1] // 2] = mass_weight
    target = image_coefficients(weights, bandwidths)
    nufft = make_nufft(backend, (bandwidths[0] + 1, bandwidths[1] + 1), epsilon, threads)
    tone = tone_radius(weights, n_points)
    radius = tone if radius is None else radius
    if not isinstance(radius, (int, float, np.floating)) or not 0 < radius < np.inf:
        raise StippleError(f"radius must be a positive number, not {radius!r}")
    objective = DiscDiscrepancy(nufft, kernel, target, scale, epsilon)
    manifold = DiscTorus(scale, balanced_size_metric(kernel, scale, radius), np.log(np.pi * radius**2))
    return DiscProblem(objective, manifold, bandwidth, scale, tone, float(mass_weight))


@dataclass
class DiscResult:
    """Outcome of ``optimise_discs``.

    ``points`` ``(M, 2)`` in unit coordinates [0, 1)² (x right, y down; times ``(W, H)`` for pixels), ``radii``
    ``(M,)`` in physical units (times ``max(W, H)`` for pixels); ``energies`` the disc energy ``E`` per
    iteration (``energies[0]`` at the start); ``status`` and ``message`` as ``stipple.optimize.minimize``'s.
    """

    points: np.ndarray
    radii: np.ndarray
    status: str
    message: str
    iterations: int
    energies: np.ndarray
    seconds: float
    bandwidth: int
    rank: int


def optimise_discs(
    weights,
    points,
    radii=None,
    bandwidth=None,
    *,
    iterations=DEFAULT_ITERATIONS,
    tol=DEFAULT_TOL,
    settle=DEFAULT_SETTLE,
    time_limit=None,
    threads=None,
    epsilon=DEFAULT_EPSILON,
    backend="ducc0",
    seed=0,
    mass_weight=None,
    beta="hestenes-stiefel",
    safeguard=False,
    sizes=True,
):
    """Optimise the positions and the sizes of discs together so that their ink reproduces ``weights``.

    Parameters
    ----------
    weights : array_like of shape (H, W), or a path
        Ink density ``w >= 0`` (the darkness), or an image / ``.npy`` file read by ``load_density``.
    points : numpy.ndarray of shape (M, 2), or int
        Starting positions in unit coordinates (e.g. ``halftone_torus(...).points``), or a number of dots M
        to start from a stratified sample of the density drawn with ``seed``.
    radii : float or numpy.ndarray of shape (M,), optional
        Starting radii in physical units (the longer side is 1), each in (0, 0.25 min(W, H) / max(W, H)];
        default the tone radius ``sqrt(mean(w) A / (pi M))`` for every disc.
    bandwidth : int, optional
        Even bandwidth N (default ``stipple.torus.default_bandwidth(M, weights)``).
    iterations : int
        Maximum number of CG iterations, >= 0.
    tol : float
        Stop when the gradient norm has fallen by this factor, > 0.
    settle : float
        Stop when 20 iterations lowered the energy by less than this fraction of it, in [0, 1) (default 0: never;
        the energy can stall for 20 iterations and fall again).
    time_limit : float, optional
        Seconds after which to stop.
    threads, epsilon, backend, mass_weight :
        See ``disc_problem``.
    seed : int
        Seed of the stratified start when ``points`` is a count.
    beta : {"hestenes-stiefel", "daniel"}
    safeguard : bool
        Halve Newton steps that would raise the energy.
    sizes : bool
        Optimise the sizes too (default); False moves the positions only, the discs keeping ``radii`` (a control:
        what the disc model does through positions alone).

    Returns
    -------
    DiscResult
    """
    started = time.perf_counter()
    if isinstance(weights, (str, os.PathLike)):
        weights = load_density(weights)
    weights = check_weights(weights)
    points, radii = start_discs(weights, points, radii, seed)
    count = len(points)
    check_integer("iterations", iterations, 0, MAX_ITERATIONS)
    if not isinstance(tol, (int, float)) or not tol > 0:
        raise StippleError(f"tol must be a positive number, not {tol!r}")
    if not isinstance(settle, (int, float)) or not 0 <= settle < 1:
        raise StippleError(f"settle must be a number in [0, 1), not {settle!r}")
    if beta not in BETAS:
        raise StippleError(f"beta must be one of {', '.join(BETAS)}, not {beta!r}")
    problem = disc_problem(
        weights,
        count,
        bandwidth,
        backend=backend,
        threads=threads,
        epsilon=epsilon,
        mass_weight=mass_weight,
        radius=float(np.median(radii)),
    )
    problem.manifold.fixed_sizes = not sizes
    outcome = minimize(
        problem.objective,
        problem.manifold,
        problem.manifold.canonical(problem.pack(points, radii)),
        tol=tol,
        max_iterations=iterations,
        time_limit=time_limit,
        settle=settle,
        beta=beta,
        safeguard=safeguard,
    )
    final = outcome.points
    return DiscResult(
        points=final[:, :2].copy(),
        radii=np.sqrt(np.exp(final[:, 2]) / np.pi),
        status=outcome.status,
        message=outcome.message,
        iterations=outcome.iterations,
        energies=outcome.energies,
        seconds=time.perf_counter() - started,
        bandwidth=problem.bandwidth,
        rank=problem.objective.factors.rank,
    )


def start_discs(weights, points, radii, seed):
    """The starting positions ``(M, 2)`` and radii ``(M,)`` of ``optimise_discs``, checked (a count of points
    starts from a stratified sample of ``weights`` drawn with ``seed``; radii default to the tone radius)."""
    if isinstance(points, (int, np.integer)) and not isinstance(points, bool):
        count = check_count(points)
        points = stratified_sample(weights, np.random.default_rng(seed), count)
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 1 or not np.all(np.isfinite(points)):
        raise StippleError(f"points must be a finite (M, 2) array with M >= 1, not shape {points.shape}")
    count = check_count(len(points))
    largest = 0.25 * min(torus_scale(weights.shape))
    radii = np.asarray(tone_radius(weights, count) if radii is None else radii, dtype=np.float64)
    if radii.ndim == 0:
        radii = np.full(count, float(radii))
    if radii.shape != (count,):
        raise StippleError(f"radii must be a number or an array of shape ({count},), not shape {radii.shape}")
    bad = ~((radii > 0) & (radii <= largest))
    if np.any(bad):
        raise StippleError(
            f"radii must be in (0, {largest:.4g}] (a quarter of the shorter side), not {radii[bad][0]!r}"
        )
    return points, radii
