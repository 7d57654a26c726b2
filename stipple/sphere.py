"""Halftoning on the sphere: exact coefficients of cell maps and analytic densities, the distance kernel."""

import os
from functools import partial

import numpy as np

from .checks import is_real
from .errors import MissingInput, StippleError
from .halftone import (
    DEFAULT_SETTLE,
    MAX_BANDWIDTH,
    Problem,
    check_count,
    check_epsilon,
    check_integer,
    check_memory,
    check_threads,
    default_threads,
    hexagonal_spacing,
    run,
)
from .io.images import given_transfer, load_density, load_input
from .kernels import NearKernel, chord_profile, sphere_kernel
from .manifolds import ScaledSphere, Sphere
from .multilevel import split_sphere_points
from .nearfield import NearField, SpherePairs
from .objective import Discrepancy, SumObjective
from .peaks import peak_ratio
from .sphere_density import (
    AnalyticDensity,
    CellMap,
    UniformDensity,
    density_at,
    local_density,
    unit_vectors,
)
from .spread import spread_close_sphere
from .torus import (
    DIRECT_BLUR_SIGMA,
    SOLVE_BANDWIDTH_FACTOR,
    STIFFNESS_CELLS_PER_SPACING,
    cell_means,
    check_bandwidth_factor,
    check_weights,
    derivative_accuracy,
    pair_share,
    periodic_blur,
    stiffness,
)
from .transforms import SphereFourier, alm_degrees_orders, spherical_angles

DEFAULT_EPSILON = 1e-10
# --uniform (the design term): transforms to 1e-12 and CG on to a relative gradient of 1e-6 (in practice the
# 2000-iteration cap): with 1e-10 and 1e-4 the degree-128 error at M = 10000 stayed at 1.6e-6 of i.i.d.,
# with these 7.8e-9.
DESIGN_EPSILON = 1e-12
DESIGN_TOL = 1e-6
# The paper's Fig. 5.3 (M = 200000, N = 1000): N = 2.236 sqrt(M) = 8.52 / (hexagonal spacing of M dots).
MODES_PER_SPACING = 8.52
# Near-field chordal radius times the degree: eps = 3 pi / N, as on the torus (eps = 3 / (2 rho_max) with the
# highest frequency rho_max = N / (2 pi) of degree N).
NEAR_FIELD_REACH = 3 * np.pi
NEAR_FIELD_SPACINGS = 5.0
# Maps stop when 20 iterations gain less than this fraction of the energy (``stipple.halftone.run``'s settle), as
# images on the torus do. At 3e-3 the topography (M = 200000) kept the old quality in 0.46x the time, but held-out
# maps (a 2:1 photo, the three Gaussians; M = 50000) ended 1.15-1.32 % above the old run's energy; at 2e-3 they
# end 0.92-1.02 % above it in 0.36x and 0.56x (docs/performance.md).
MAP_SETTLE = DEFAULT_SETTLE
# Uniform points (no map) stop by ``tol``, and also when the energy stops falling (less than this fraction of it
# over ``SETTLE_WINDOW`` iterations): the run has stalled at rounding. One point on the uniform sphere, whose
# gradient is rounding noise, ran all 2000 iterations (a held-out review); designs stall the same way.
STALLED = 1e-12


def default_bandwidth(n_points, density=None):
    """Degree N from the dots' mean spacing and, given a density, its peak (as ``stipple.torus.default_bandwidth``).

    ``N = 8.52 / s`` (the paper's ``2.24 sqrt(M)``), raised where the density is peaked so that the near-field
    radius ``3 pi / N`` is at most five local spacings of the densest region (at most ``MAX_BANDWIDTH``).
    """
    spacing = hexagonal_spacing(n_points, 4 * np.pi)
    bandwidth = MODES_PER_SPACING / spacing
    if density is not None and not isinstance(density, UniformDensity):
        cells = density.cell_map()
        densest = spacing / np.sqrt(peak_ratio(cells.values, cells.cell_areas))
        bandwidth = max(bandwidth, NEAR_FIELD_REACH / (NEAR_FIELD_SPACINGS * densest))
    return min(int(np.ceil(bandwidth)), MAX_BANDWIDTH)


def design_degree(n_points):
    """``floor(0.96 sqrt(2M))``: nearly the highest degree up to which M points can integrate every harmonic
    exactly (a design of strength t needs about t²/2 points; Gräf & Potts). Measured at M = 10000: with
    ``0.9 sqrt(2M)`` (127) the error at degree 128 stayed at the Fibonacci lattice's; with 135 it was 34 times
    lower."""
    return max(1, int(0.96 * np.sqrt(2 * n_points)))


def default_kernel(density, n_points):
    """``distance`` for maps; for the uniform density ``distance+design:T`` with ``T = design_degree(M)``.

    Measured at M = 10000 against the spherical Fibonacci lattice: the distance kernel alone (its untruncated
    energy is the L2 cap discrepancy, by Stolarsky's principle) beat it on Coulomb energy and cap discrepancy but
    not on the bandlimited error at degree 128 (1e-5 against 7e-7 of i.i.d.); with the design term (T = 135) on
    all three (2.1e-8, README "Spherical designs").
    """
    return f"distance+design:{design_degree(n_points)}" if isinstance(density, UniformDensity) else "distance"


def check_degree(bandwidth):
    return check_integer("bandwidth (degree)", bandwidth, 1, MAX_BANDWIDTH)


def stiffness_map(density, n_points):
    """The metric's factor per cell (``stipple.manifolds.ScaledSphere``), as on the torus
    (``stipple.torus.stiffness_field``): the density's cell map blurred at one dot spacing (along the rows in
    latitude, periodically along the columns), over its mean (``stipple.torus.stiffness``); a ``CellMap``."""
    cells = density.cell_map()
    rows = cells.values.shape[0]
    spacing = hexagonal_spacing(n_points, 4 * np.pi) / (np.pi / rows)
    # On cells of a quarter spacing where those are two cells or more, as on the torus.
    coarse = cell_means(np.asarray(cells.values, dtype=float), spacing / STIFFNESS_CELLS_PER_SPACING)
    blurred = map_blur(coarse, max(spacing * coarse.shape[0] / rows, 0.5))
    return CellMap(stiffness(blurred, density.mean), cells.lon0)


def map_blur(values, sigma):
    """A map's cells blurred by a Gaussian of ``sigma`` cells: periodically along the columns (longitude), with the
    edge rows repeated beyond the poles (``scipy.ndimage.gaussian_filter``, modes "nearest" and "wrap"). Wider
    than ``DIRECT_BLUR_SIGMA`` through the FFT of the map padded by the filter's reach (``periodic_blur``): a
    3000×6000 map with 300 dots took 18 s in the direct filter."""
    if sigma <= DIRECT_BLUR_SIGMA:
        from scipy.ndimage import gaussian_filter

        return gaussian_filter(values, sigma, mode=("nearest", "wrap"))
    reach = int(np.ceil(4 * sigma))  # the direct filter's truncation
    padded = np.pad(values, ((reach, reach), (0, 0)), mode="edge")
    return periodic_blur(padded, sigma)[reach:-reach]


def lon_lat(points):
    """Longitude in (-180, 180] and latitude in [-90, 90], degrees, of unit vectors."""
    theta, phi = spherical_angles(points)
    longitude = np.degrees(phi)
    return np.where(longitude > 180, longitude - 360, longitude), 90 - np.degrees(theta)


def from_lon_lat(longitude, latitude):
    return unit_vectors(np.sin(np.radians(latitude)), np.radians(longitude))


def as_density(weights, lon0=0.0):
    """A density object from a map array, a callable on unit vectors, a density object, or None (uniform)."""
    if weights is None:
        return UniformDensity()
    if hasattr(weights, "coefficients"):
        return weights
    if callable(weights):
        return AnalyticDensity(weights)
    if isinstance(weights, (str, os.PathLike)):
        weights = load_density(weights)
    return CellMap(weights, lon0)


def check_lon0(lon0):
    """``lon0`` as a float in [-360, 360] (as ``--lon0``): NaN failed in ducc0's assertion, and 360 * 2**60
    was a different map, its longitudes rounded away."""
    if not is_real(lon0) or not -360 <= lon0 <= 360:
        raise StippleError(f"lon0 must be a number of degrees in [-360, 360], not {lon0!r}")
    return float(lon0)


def unit_peak(density):
    """A map scaled to a largest value of 1 (the problem is the same at any scale; maps are read so, but a pen's
    clip, ``stipple.pipelines.pen.sphere_pen_density``, can bring one to 5e-36, where the single-precision
    derivatives underflow: 20 iterations, the dots in two clusters); other densities as they are."""
    if not isinstance(density, CellMap) or density.values.max() in (0.0, 1.0):
        return density
    return CellMap(density.values / density.values.max(), density.lon0)


def sphere_problem(
    weights,
    n_points,
    bandwidth=None,
    *,
    lon0=0.0,
    kernel=None,
    threads=None,
    epsilon=None,
    near_field=None,
    precondition=True,
    bandwidth_factor=SOLVE_BANDWIDTH_FACTOR,
    derivative_epsilon=None,
):
    """The halftoning problem of ``weights`` (see ``halftone_sphere``) with ``n_points`` dots on S².

    A map with the distance kernel and its near field (the default for maps) is solved as on the torus: without a
    ``bandwidth`` at ``bandwidth_factor`` times ``default_bandwidth`` (the near field keeps the objective
    untruncated at any N), with ``precondition`` in the metric scaled by ``stiffness_map``, from the
    coarse-to-fine start where ``run`` starts "stratified" (``level`` and ``split``), ending with the spread step
    (``stipple.spread.spread_close_sphere``) and stopping by ``settle`` (``MAP_SETTLE``), its derivatives'
    transforms at ``derivative_epsilon`` (default ``epsilon``; ``stipple sphere`` asks for
    ``stipple.torus.DERIVATIVE_EPSILON``, single precision, as ``stipple torus`` does). Designs and the Sobolev
    kernel keep their bandwidth, the plain metric, their start and ``epsilon`` throughout (``derivative_epsilon``
    is ignored there).
    """
    density = unit_peak(as_density(weights, check_lon0(lon0)))
    n_points = check_count(n_points)
    kernel = default_kernel(density, n_points) if kernel is None else kernel
    if not isinstance(kernel, str):
        raise StippleError(f"kernel must be a name such as 'distance' or 'sobolev:1', not {kernel!r}")
    near_field = kernel.startswith("distance") if near_field is None else bool(near_field)
    if near_field and not kernel.startswith("distance"):
        raise StippleError(f"the near field needs the distance kernel, not {kernel!r}")
    picture = near_field and kernel == "distance"
    if bandwidth is None:
        bandwidth = default_bandwidth(n_points, density)
        if picture:
            bandwidth = int(np.ceil(bandwidth * check_bandwidth_factor(bandwidth_factor)))
    bandwidth = check_degree(bandwidth)
    if epsilon is None:
        epsilon = DESIGN_EPSILON if kernel.startswith("distance+design") else DEFAULT_EPSILON
    # ducc0's general SHTs work on a doubled-sphere grid of about (2N)^2 complex values. Measured peaks: a 4-degree
    # peak at M = 500000 (N = 4933) 7.4 GiB; at M = 2e7 (N = 5735) over 22 GiB, killed by the kernel, which the
    # earlier 16 (N+1)^2 x 16 + 480 M bytes (16.8 GiB) let through (a held-out review).
    check_memory(20 * 16 * (bandwidth + 1) ** 2 + 120 * 8 * n_points, f"M={n_points}, N={bandwidth}")
    threads = default_threads() if threads is None else check_threads(threads)
    derivative_epsilon = derivative_accuracy(epsilon, derivative_epsilon if picture else None)
    accuracy = (epsilon, derivative_epsilon)
    objective, discrepancy = sphere_objective(density, n_points, bandwidth, kernel, near_field, threads, accuracy)
    scaled = picture and precondition
    manifold = (
        ScaledSphere(partial(density_at, stiffness_map(density, n_points)), threads) if scaled else Sphere(threads)
    )
    # The same map with other counts: the coarse-to-fine start's levels (``stipple.multilevel``).
    same = partial(
        sphere_problem,
        density,
        kernel=kernel,
        threads=threads,
        epsilon=epsilon,
        precondition=precondition,
        bandwidth_factor=bandwidth_factor,
        derivative_epsilon=derivative_epsilon,
    )
    return Problem(
        domain="sphere",
        manifold=manifold,
        objective=objective,
        discrepancy=discrepancy,
        n_points=n_points,
        bandwidth=bandwidth,
        sample=density.sample,
        settle=MAP_SETTLE if picture else STALLED,
        stratified=density.stratified if picture else None,
        level=same if picture else None,
        split=partial(split_sphere_points, density.cell_map(), threads=threads) if picture else None,
        spread=partial(spread_sphere_points, density, threads=threads) if picture else None,
        settings={
            "domain": "sphere",
            "points": n_points,
            "bandwidth": bandwidth,
            "kernel": kernel,
            "near_field": near_field,
            "hessian": "gauss-newton",
            "metric": "density" if scaled else "flat",
        },
    )


def spread_sphere_points(density, points, threads=1):
    """The spread step (``stipple.spread``) of ``points`` at ``density``'s dots per steradian."""
    return spread_close_sphere(points, local_density(density, points), threads=threads)


def sphere_objective(density, n_points, bandwidth, kernel, near_field, threads, accuracy):
    """``(objective, discrepancy)`` of ``n_points`` dots on ``density`` at degree ``bandwidth``: the kernel's
    discrepancy, with the near field of the distance kernel added where asked. ``accuracy``: ``(epsilon,
    derivative_epsilon)`` of the transforms (``SphereFourier``)."""
    epsilon, derivative_epsilon = (check_epsilon(value) for value in accuracy)
    target = density.coefficients(bandwidth, threads)
    degrees, _ = alm_degrees_orders(bandwidth)
    kernel_coeffs = sphere_kernel(kernel, degrees)
    # The adjoints run on one thread (their order of addition is then fixed: the same bits every run for a thread
    # count), beside the pairs; the syntheses keep every thread. The pairs' blocks are spread over every thread
    # too: the adjoint of ``set_points`` takes half as long as the pairs' search, and the pairs' second block
    # fills the thread it leaves (docs/performance.md, eleventh round).
    pair_threads = pair_share(threads) if near_field else 0
    fourier = SphereFourier(bandwidth, epsilon, threads, adjoint_threads=1, derivative_epsilon=derivative_epsilon)
    weight = target[0].real * np.sqrt(4 * np.pi) / n_points
    if not near_field:
        discrepancy = Discrepancy(fourier, kernel_coeffs, target, weight)
        return discrepancy, discrepancy
    near = NearKernel(chord_profile, min(NEAR_FIELD_REACH / bandwidth, 0.5))
    cross_kernel = near.sphere_coefficients(bandwidth)[degrees]
    discrepancy = Discrepancy(fourier, kernel_coeffs - cross_kernel, target, weight, cross_kernel=cross_kernel)
    pairs = NearField(near, weight, SpherePairs(), threads=threads)
    return SumObjective(discrepancy, pairs, concurrent=pair_threads > 0), discrepancy


def halftone_sphere(
    weights,
    n_points,
    bandwidth=None,
    *,
    lon0=0.0,
    kernel=None,
    threads=None,
    epsilon=None,
    near_field=None,
    derivative_epsilon=None,
    **options,
):
    """Place ``n_points`` dots on the unit sphere so that they reproduce a density.

    Parameters
    ----------
    weights : array_like (H, W), path, callable, density object, or None
        An equirectangular map of ``w >= 0`` (row 0 at the north pole, column 0 starting at ``lon0``
        degrees east) or a file read by ``stipple.load_density``, a function of unit vectors
        ``(M, 3) -> (M,)``, or None for ``w ≡ 1`` (numerical spherical designs).
    n_points : int
        Number of dots M.
    bandwidth : int, optional
        Polynomial degree N of the kernel (default ``default_bandwidth(M)``).
    lon0 : float
        Longitude (degrees east) where the map's first column starts.
    kernel : str, optional
        ``"distance"`` (the paper's; default for maps), ``"distance+design:T"`` (default for ``w ≡ 1``, with
        ``T = design_degree(M)``) or ``"sobolev:S"`` (see ``stipple.kernels.sphere_kernel``).
    threads : int, optional
        Threads for the transforms (default: all usable CPUs; ducc0's spherical transforms are
        deterministic for a fixed thread count).
    epsilon : float, optional
        Requested accuracy of the transforms (default 1e-10; 1e-12 with the design term, where ``tol=1e-6`` is
        also worth passing, as the CLI does).
    derivative_epsilon : float, optional
        Accuracy of a map's derivative transforms (default ``epsilon``; ``stipple sphere`` passes
        ``stipple.torus.DERIVATIVE_EPSILON``, single precision: see ``sphere_problem``).
    near_field : bool, optional
        Minimise the untruncated distance discrepancy with its short range summed over neighbouring pairs
        (default for the distance kernel); False gives the paper's bandlimited ``E_N``.
    **options
        As for ``halftone_torus``; ``init`` may be an (M, 3) array (normalised onto the sphere).

    Returns
    -------
    HalftoneResult
        ``points`` as unit vectors of shape (M, 3); ``stipple.sphere.lon_lat`` converts them.
    """
    problem = sphere_problem(
        weights,
        n_points,
        bandwidth,
        lon0=lon0,
        kernel=kernel,
        threads=threads,
        epsilon=epsilon,
        near_field=near_field,
        derivative_epsilon=derivative_epsilon,
    )
    return run(problem, **options)


def three_gaussians(points):
    """Paper Fig. 5.4: ``sum_i exp(-5 arccos(x . q_i)^2)`` with ``q_i`` the coordinate axes."""
    return np.sum(np.exp(-5 * np.arccos(np.clip(points, -1, 1)) ** 2), axis=1)


def rbf_node_density(points):
    """Paper Fig. 5.5, eq. (5.2): ``sqrt(3) sech^2(3s) tanh(3s) / (2s)``, ``s = sin(theta)``; 3 sqrt(3)/2 at poles."""
    s = np.sqrt(np.clip(1 - points[:, 2] ** 2, 0, None))
    safe = np.where(s > 0, s, 1.0)
    value = np.sqrt(3) * np.tanh(3 * safe) / np.cosh(3 * safe) ** 2 / (2 * safe)
    return np.where(s > 0, value, 1.5 * np.sqrt(3))


BUILTINS = {
    "gaussians": AnalyticDensity(three_gaussians, "builtin:gaussians"),
    "rbf": AnalyticDensity(rbf_node_density, "builtin:rbf"),
    "uniform": UniformDensity(),
}


def picture_darkness(density):
    """``darkness_at(lon, lat)`` in [0, 1] that a tone-true picture of ``density`` draws (the density, divided
    by its largest value where that exceeds 1), or None for the uniform density, whose picture shows points."""
    if isinstance(density, UniformDensity):
        return None
    cells = density.cell_map()
    scale = max(1.0, float(cells.values.max()))
    return lambda longitude, latitude: cells.at(longitude, latitude) / scale


def sphere_density(source, *, uniform=False, invert=False, gamma=1.0, value_range=None, lon0=0.0):
    """The density of a map (``-`` is stdin), a built-in name (``builtin:NAME``) or, with ``uniform``, w ≡ 1.

    ``invert``, ``gamma`` and ``value_range`` transform a map's or an image's values; given with a built-in
    density they are refused (they would be ignored), and so are ``gamma`` and ``value_range`` with ``uniform``
    (whose ``--invert`` only draws white dots on black)."""
    if uniform:
        if source is not None:
            raise StippleError("give either MAP or --uniform, not both")
        _refuse_transfer("--uniform", False, gamma, value_range)
        return BUILTINS["uniform"]
    if source is None:
        raise MissingInput("missing MAP (a .npy map, an image, builtin:NAME) or --uniform")
    if source.startswith("builtin:"):
        name = source.partition(":")[2]
        if name not in BUILTINS:
            raise StippleError(f"unknown built-in density {name!r}; choose from {', '.join(BUILTINS)}")
        _refuse_transfer(source, invert, gamma, value_range)
        return BUILTINS[name]
    # A blank one named as the map's file, not "map" (an all-clear PNG; a hostile review).
    return CellMap(check_weights(load_input(source, invert=invert, gamma=gamma, value_range=value_range), source), lon0)


def _refuse_transfer(what, invert, gamma, value_range):
    """One line naming the map options given with a density that has no map values to transform."""
    given = given_transfer({"invert": invert, "gamma": gamma, "value_range": value_range})
    if given:
        verb = "transforms" if len(given) == 1 else "transform"
        colours = " (--background and --color draw white dots on black)" if invert else ""
        raise StippleError(f"{', '.join(given)} {verb} a map's or an image's values, not {what}{colours}")
