"""Halftoning on the torus: the problem (default bandwidth, stiffness field, objective) and the run; its Fourier
side (an image's exact coefficients, the ball-discrepancy kernel) is ``stipple.torus_spectrum``."""

import os
from functools import partial

import numpy as np

from .errors import StippleError
from .halftone import (
    DEFAULT_SETTLE,
    FLAT_SETTLE,
    MAX_BANDWIDTH,
    Problem,
    check_bandwidth,
    check_count,
    check_epsilon,
    check_memory,
    check_threads,
    default_threads,
    even_at_least_2,
    hexagonal_spacing,
    run,
)
from .io.images import check_grid, load_density
from .manifolds import ScaledTorus, Torus
from .multilevel import split_points
from .nearfield import NearField, TorusPairs
from .nufft import BACKENDS, make_nufft
from .objective import Discrepancy, SumObjective
from .peaks import peak_ratio
from .sampling import sample_image, stratified_sample
from .spread import spread_close
from .torus_spectrum import NEAR_FIELD_REACH, PixelDensity, axis_bandwidths, torus_kernels, torus_scale
from .transforms import TorusFourier

# Transform accuracy: at M = 10^6 the energy after 8 CG iterations moved by 4e-9 of itself against 1e-9, at
# 10 % less time per iteration (README, Defaults).
DEFAULT_EPSILON = 1e-7
# Accuracy asked of the derivatives' transforms by ``stipple torus`` (gradient and Hessian forms, in single precision:
# ``stipple.precision.precision``); the residual keeps ``epsilon``. Measured on the portrait and at M = 200000
# after 40 iterations: the gradient within 1.4e-5 of the double-precision one, the Hessian form within 2e-8, the
# same energies to 8 digits after 60 iterations (docs/performance.md).
DERIVATIVE_EPSILON = 1e-4


def derivative_accuracy(epsilon, derivative_epsilon=None):
    """The derivatives' accuracy: ``derivative_epsilon`` (checked), never finer than ``epsilon``; default
    ``epsilon``."""
    if derivative_epsilon is None:
        return epsilon
    return max(check_epsilon(derivative_epsilon, "derivative_epsilon"), epsilon)


# The paper's Fig. 5.1 (M = 30150, N = 650 on a square): N = 4.02 / (hexagonal spacing of M dots).
MODES_PER_SPACING = 4.02
# The default bandwidth keeps the near field at most this many local spacings wide where the density peaks
# (about 90 pairs per dot there): fewer modes, more pairs; the transforms cost more than the pairs.
NEAR_FIELD_SPACINGS = 5.0


def default_bandwidth(n_points, weights=None):
    """Bandwidth N along the longer side, from the dots' spacing and, given ``weights``, the density's peak.

    ``N = 4.02 / s`` with ``s`` the mean hexagonal spacing of M dots on the image's rectangle (the paper's ratio,
    ``N = 3.74 sqrt(M)`` on a square; a 6:1 strip gets ``sqrt(6)`` times more). Where the density is peaked,
    ``N`` is raised so that the near-field radius ``3/N`` stays within ``NEAR_FIELD_SPACINGS`` local spacings of
    the densest region (see ``peak_ratio``), which bounds the pairs per dot. Even, at most ``MAX_BANDWIDTH``.
    """
    shape = (1, 1) if weights is None else np.shape(weights)
    spacing = hexagonal_spacing(n_points, np.prod(torus_scale(shape)))
    bandwidth = MODES_PER_SPACING / spacing
    if weights is not None:
        peak = weights.peak_ratio if isinstance(weights, PixelDensity) else peak_ratio(weights)
        densest = spacing / np.sqrt(peak)
        bandwidth = max(bandwidth, NEAR_FIELD_REACH / (NEAR_FIELD_SPACINGS * densest))
    return min(int(2 * np.ceil(bandwidth / 2)), MAX_BANDWIDTH)


# The default run solves at this fraction of ``default_bandwidth`` (the near field's radius 3/N grows to match):
# the same untruncated objective, the transforms' grids half as large. On the portrait after 100 iterations:
# N = 650, 460, 326 gave exact-blur PSNR at 1 px 39.2, 39.5, 39.3 dB and p01 0.718, 0.716, 0.700; at M = 10^6 an
# iteration took 0.84 times as long (docs/performance.md).
SOLVE_BANDWIDTH_FACTOR = 0.7
# The metric's factor (``stiffness_field``): the density blurred at one dot spacing, over its mean, to this power,
# at least STIFFNESS_FLOOR. On the portrait the exact-blur PSNR at 1 px after 60 iterations was 37.9 dB with the
# flat metric, 38.8 with the power 0.5, 39.2 with 1 and 39.3 with 1.5 (whose energy and p01 were worse); see
# docs/performance.md.
STIFFNESS_POWER = 1.0
STIFFNESS_FLOOR = 0.02


def stiffness_field(weights, n_points):
    """Per pixel, the factor of the torus metric (``ScaledTorus``): how stiff the dots' arrangement is there.

    A dot's restoring force against a small move grows with the local density (more neighbours, closer), so
    CG's one step per iteration, sized by the stiffest region, moves the dots of light regions too little. The
    factor is ``max(w_b / mean(w_b), STIFFNESS_FLOOR) ** STIFFNESS_POWER`` with ``w_b`` the density blurred
    (periodically) at the mean dot spacing.
    """
    spacing = hexagonal_spacing(n_points, np.prod(torus_scale(weights.shape))) * max(weights.shape)
    cells = cell_means(weights, spacing / STIFFNESS_CELLS_PER_SPACING)
    blurred = periodic_blur(cells, max(spacing * max(cells.shape) / max(weights.shape), 0.5))
    return stiffness(blurred, blurred.mean())


# The stiffness field is made on cells of a quarter of a dot spacing or of one pixel, whichever is larger: a blur at
# one spacing needs no finer grid (a 12-megapixel photo with 30000 dots: 0.7 s a field on its pixels).
STIFFNESS_CELLS_PER_SPACING = 4


def cell_means(values, size):
    """``values`` averaged over cells of ``size`` pixels or a little less along each axis (``values`` itself below
    2), uniform over the image as ``ScaledTorus`` reads its field: each pixel to the cell its centre lies in."""
    factor = int(size)
    if factor < 2:
        return values
    for axis, length in enumerate(values.shape):
        cells = -(-length // factor)
        owner = ((np.arange(length) + 0.5) * cells / length).astype(np.intp)
        starts = np.searchsorted(owner, np.arange(cells))
        counts = np.diff(np.append(starts, length))
        values = np.add.reduceat(values, starts, axis=axis) / np.expand_dims(counts, 1 - axis)
    return values


# Blurs wider than this (pixels) go through the FFT: a direct filter's time grows with the width (a 9000² image
# with 300 dots blurred at 560 px for minutes, in C, where no signal could stop it).
DIRECT_BLUR_SIGMA = 16.0


def periodic_blur(values, sigma):
    """``values`` (H, W) blurred by a Gaussian of ``sigma`` pixels, periodically: ``scipy.ndimage.gaussian_filter``
    (mode "wrap") up to ``DIRECT_BLUR_SIGMA``, beyond it the same Gaussian's Fourier transform applied to the
    image's FFT (in a time independent of ``sigma``)."""
    if sigma <= DIRECT_BLUR_SIGMA:
        from scipy.ndimage import gaussian_filter

        return gaussian_filter(values, sigma, mode="wrap")
    spectrum = np.fft.rfft2(values)
    rows, columns = (
        np.exp(-2 * (np.pi * sigma * frequencies) ** 2)
        for frequencies in (np.fft.fftfreq(values.shape[0]), np.fft.rfftfreq(values.shape[1]))
    )
    spectrum *= rows[:, None]
    spectrum *= columns[None, :]
    return np.fft.irfft2(spectrum, s=values.shape)


def check_bandwidth_factor(bandwidth_factor):
    """``bandwidth_factor`` if it is a number in (0, 1], else a ``StippleError`` naming it."""
    if not (isinstance(bandwidth_factor, (int, float)) and 0 < bandwidth_factor <= 1):
        raise StippleError(f"bandwidth factor must be a number in (0, 1], not {bandwidth_factor!r}")
    return bandwidth_factor


def stiffness(blurred, mean):
    """The metric's factor from the density blurred at one dot spacing: ``max(blurred / mean, STIFFNESS_FLOOR) **
    STIFFNESS_POWER``."""
    return np.maximum(blurred / mean, STIFFNESS_FLOOR) ** STIFFNESS_POWER


def check_weights(weights, source=None):
    """``weights`` as a finite, non-negative, not all zero grid of float64 (complex values and masked arrays are
    refused: numpy dropped their imaginary part or mask without a word); a blank one named as ``source`` if
    given."""
    if np.ma.isMaskedArray(weights):
        raise StippleError("weights: a masked array; fill its masked cells first (e.g. weights.filled(0))")
    values = np.asarray(weights)
    if values.dtype.kind not in "biuf":
        raise StippleError(f"weights must be real numbers, not {values.dtype}")
    weights = check_grid(values.astype(np.float64), "weights")
    if np.any(weights < 0):
        raise StippleError("weights must be non-negative")
    if not np.any(weights > 0):
        named = "" if source is None else f"{source}: "
        raise StippleError(
            f"{named}the image is blank (all white) or the map zero everywhere: there is nothing to place dots on"
        )
    return weights


# The dots are the same at any scale of the weights, but far from 1 the energy's squares under- or overflow (at
# 1e-80 a run stopped as "converged" at its start, at 1e80 with a NaN energy; a hostile review): weights whose
# largest value lies outside WEIGHT_SCALES are divided by it.
WEIGHT_SCALES = (1e-12, 1e12)


def unit_scaled(weights, peak=None):
    """``weights`` over ``peak`` (default their largest value) where that lies outside ``WEIGHT_SCALES``."""
    peak = float(weights.max()) if peak is None else peak
    return weights if WEIGHT_SCALES[0] <= peak <= WEIGHT_SCALES[1] else weights / peak


def torus_problem(
    weights,
    n_points,
    bandwidth=None,
    *,
    backend="ducc0",
    threads=None,
    epsilon=DEFAULT_EPSILON,
    hessian="gauss-newton",
    near_field=True,
    precondition=True,
    bandwidth_factor=SOLVE_BANDWIDTH_FACTOR,
    derivative_epsilon=None,
):
    """The halftoning problem of ``weights`` (rows top to bottom, an image file, or a ``PixelDensity`` whose FFT and
    peak its problems share) with ``n_points`` dots on T².

    Without a ``bandwidth`` it is ``bandwidth_factor`` times ``default_bandwidth`` (even; the low-frequency
    correction still divides ``default_bandwidth``); measures that compare with the kernel's ``E_N`` pass
    ``default_bandwidth`` itself. With ``precondition`` (default) CG works in the metric scaled by the
    density's ``stiffness_field``. The problem's ``level(count)`` is the same problem with ``count`` dots at its
    own default bandwidth and ``split(points, count)`` turns a level's points into ``count``
    (``stipple.multilevel``), for the coarse-to-fine start of ``run``. The residual's transforms have the accuracy
    ``epsilon``, the derivatives' ``derivative_epsilon`` (``derivative_accuracy``; default ``epsilon``, and
    ``DERIVATIVE_EPSILON`` for ``stipple torus``), kept by the levels and the coarse problems.
    """
    if isinstance(weights, (str, os.PathLike)):
        weights = load_density(weights)
    density = weights if isinstance(weights, PixelDensity) else PixelDensity(unit_scaled(check_weights(weights)))
    weights = density.weights
    n_points = check_count(n_points)
    correction_bandwidth = bandwidth
    if bandwidth is None:
        correction_bandwidth = default_bandwidth(n_points, density)
        bandwidth = even_at_least_2(correction_bandwidth * check_bandwidth_factor(bandwidth_factor))
    bandwidth = check_bandwidth(bandwidth)
    threads = default_threads() if threads is None else check_threads(threads)
    if backend not in BACKENDS:
        raise StippleError(f"backend must be one of {', '.join(BACKENDS)}, not {backend!r}")
    shape = tuple(n + 1 for n in axis_bandwidths(bandwidth, weights.shape))
    # The GPU's transforms keep the measured path: they were never run from a second thread (no GPU to check on).
    pair_threads = pair_share(threads) if near_field and backend != "cufinufft" else 0
    transform_threads = threads - pair_threads
    derivative_threads = shared_derivative_threads(transform_threads, pair_threads, shape)
    point_bytes = POINT_BYTES + THREAD_POINT_BYTES * (threads + 2 * (derivative_threads > transform_threads))
    check_memory(GRIDS * 16 * 1.6 * (bandwidth + 1) ** 2 + point_bytes * n_points, f"M={n_points}, N={bandwidth}")
    epsilon = check_epsilon(epsilon)
    derivative_epsilon = derivative_accuracy(epsilon, derivative_epsilon)
    scale = torus_scale(weights.shape)
    nufft = make_nufft(backend, shape, derivative_epsilon, derivative_threads)
    fourier = TorusFourier(nufft, analysis_epsilon=epsilon, analysis_threads=transform_threads)
    objective, discrepancy = torus_objective(density, n_points, bandwidth, fourier, hessian, near_field, pair_threads)
    manifold = ScaledTorus(scale, stiffness_field(weights, n_points)) if precondition else Torus(scale)
    # The same image with other counts or bandwidths: the correction's coarse problems and the start's levels.
    same = partial(
        torus_problem,
        density,
        backend=backend,
        threads=threads,
        epsilon=epsilon,
        precondition=precondition,
        derivative_epsilon=derivative_epsilon,
    )
    return Problem(
        domain="torus",
        manifold=manifold,
        objective=objective,
        discrepancy=discrepancy,
        n_points=n_points,
        bandwidth=bandwidth,
        sample=lambda rng, count: sample_image(weights, rng, count),
        stratified=lambda rng, count: stratified_sample(weights, rng, count),
        settle=DEFAULT_SETTLE if precondition else FLAT_SETTLE,
        correction_bandwidth=min(correction_bandwidth, MAX_BANDWIDTH),
        coarse=lambda coarse_bandwidth: same(n_points, coarse_bandwidth, near_field=False),
        level=lambda count: same(count, hessian=hessian, near_field=near_field, bandwidth_factor=bandwidth_factor),
        split=lambda points, count: split_points(weights, points, count, scale, threads),
        spread=(lambda points: spread_close(points, weights, threads=threads)) if precondition else None,
        settings={
            "domain": "torus",
            "points": n_points,
            "bandwidth": bandwidth,
            "kernel": "ball",
            "near_field": bool(near_field),
            "hessian": hessian,
            "shape": list(weights.shape),
            "metric": "density" if precondition else "flat",
        },
    )


# A run's memory (``torus_problem``'s check): GRIDS complex mode grids, oversampled, and POINT_BYTES a point, with
# THREAD_POINT_BYTES more for each thread (each residue class of the type-1 transforms keeps the points' phases
# and its plan's copy of them; two more where the derivatives share the pairs' thread). Whole default commands
# with 2 threads peaked at 2.50 GiB for 10^6 points at N = 2620 (estimated 2.41; 2.57 since the sharing, estimated
# 2.56), 2.19 GB for a small dark spot on a white page, 10^4 points at N = 3120 (2.25); with
# 16 threads 10^6 points peaked at 3.45 GiB (estimated 3.46; a 16-core machine), and M = 200000 at 0.72 GiB
# against 0.60 with 2 (`--threads 16` on 2 cores).
# Twelve grids and 320 bytes a point estimated 20 million points on a 48 x 32 image at 15.4 GiB, which passed on a
# machine with 22.8 GiB available, and the kernel's OOM killer ended the run at 23.5 GB; now 25.7 GiB, refused.
GRIDS, POINT_BYTES, THREAD_POINT_BYTES = 9, 850, 80


# Grids of more rows than this give the derivatives' transforms the pairs' thread too, where each has one.
SHARED_DERIVATIVE_ROWS = 2000


def shared_derivative_threads(transform_threads, pair_threads, shape):
    """Threads of the derivatives' transforms (the gradient's type-2 and the Hessian form's type-1): the
    transforms' share, or, with one thread each for the transforms and the pairs, both on a grid of more than
    ``SHARED_DERIVATIVE_ROWS`` rows. The pairs' gradient and form are a small part of those phases, so their thread
    idles there (M = 10^6, N = 2620: the whole default command 0.95x the time, 104 against 109 s, 140 MB more for
    the residue classes' copies of the points; M = 200000 and the portrait gained nothing or lost,
    docs/performance.md, nineteenth round). The residual's transform keeps one thread beside the pairs' search."""
    if transform_threads == 1 and pair_threads == 1 and shape[0] > SHARED_DERIVATIVE_ROWS:
        return 2
    return transform_threads


def pair_share(threads):
    """The near field's share of ``threads`` (0: none of its own). With two or more the transforms and the pairs
    run at once, each on its share (``SumObjective(concurrent=True)``): on 2 cores the portrait's run took 0.77×
    the time of both on both threads one after the other, M = 200000 0.91×, M = 10⁶ 0.96× (docs/performance.md)."""
    return threads // 2


def torus_objective(density, n_points, bandwidth, fourier, hessian, near_field, pair_threads=0):
    """``(objective, discrepancy)`` of ``density`` (a ``PixelDensity``) with ``n_points`` dots at ``bandwidth`` on
    ``fourier``'s plan:
    the discrepancy's smooth part plus the near field's pair sums (``near_field``), or the bandlimited
    discrepancy alone. With ``pair_threads`` the pairs' own threads, the two terms are evaluated at once;
    without, the pairs use ``fourier``'s threads after the transforms."""
    scale = torus_scale(density.shape)
    bandwidths = axis_bandwidths(bandwidth, density.shape)
    target = density.coefficients(bandwidths)
    weight = density.weights.mean() / n_points
    smooth, cross_kernel, near = torus_kernels(bandwidth, density.shape, near_field)
    discrepancy = Discrepancy(fourier, smooth, target, weight, hessian, cross_kernel)
    if not near_field:
        return discrepancy, discrepancy
    threads = pair_threads or fourier.threads
    pairs = NearField(near, weight, TorusPairs(scale), factor=np.prod(scale), hessian=hessian, threads=threads)
    return SumObjective(discrepancy, pairs, concurrent=pair_threads > 0), discrepancy


def halftone_torus(
    weights,
    n_points,
    bandwidth=None,
    *,
    backend="ducc0",
    threads=None,
    epsilon=DEFAULT_EPSILON,
    hessian="gauss-newton",
    near_field=True,
    precondition=True,
    bandwidth_factor=SOLVE_BANDWIDTH_FACTOR,
    **options,
):
    """Place ``n_points`` dots on the torus so that they reproduce the density ``weights``.

    Parameters
    ----------
    weights : array_like of shape (H, W), or a path
        Density ``w >= 0`` per pixel, row 0 at the top, or an image / ``.npy`` file read by
        ``stipple.load_density`` (dark image regions get large ``w``).
    n_points : int
        Number of dots M, 1 <= M <= 20,000,000.
    bandwidth : int, optional
        Even bandwidth N of the kernel along the longer image side (default ``default_bandwidth(M)``).
    backend : {"ducc0", "finufft", "cufinufft"}
        NUFFT library; "cufinufft" runs the transforms on an NVIDIA GPU (``stipple.gpu``).
    threads : int, optional
        Threads for the transforms (default: all CPUs). On the CPU the same thread count gives the same points
        bit for bit (see ``stipple.nufft.ResidueSplitNufft``); on the GPU they agree to rounding.
    epsilon : float
        Requested accuracy of the transforms.
    hessian : {"gauss-newton", "full"}
        Hessian used by the Newton step (and by ``beta="daniel"``).
    near_field : bool
        Minimise the untruncated ball discrepancy, its short range summed over neighbouring pairs (default);
        False gives the paper's bandlimited ``E_N``.
    precondition, bandwidth_factor :
        See ``torus_problem``.
    **options
        ``init``, ``seed``, ``tol``, ``settle``, ``iterations``, ``time_limit``, ``restart_every``, ``beta``,
        ``callback``, ``checkpoint``, ``checkpoint_seconds``, ``checkpoint_iterations``, ``resume``, ``correct``,
        ``levels``:
        see ``stipple.halftone.run``. ``init`` may be an (M, 2) array in unit coordinates.

    Returns
    -------
    HalftoneResult
        ``points`` of shape (M, 2) in unit coordinates [0, 1)² (x right, y down); multiply by
        ``(W, H)`` for pixel units.
    """
    problem = torus_problem(
        weights,
        n_points,
        bandwidth,
        backend=backend,
        threads=threads,
        epsilon=epsilon,
        hessian=hessian,
        near_field=near_field,
        precondition=precondition,
        bandwidth_factor=bandwidth_factor,
    )
    return run(problem, **options)
