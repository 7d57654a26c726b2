"""Halftoning on the sphere: exact coefficients of cell maps and analytic densities, the distance kernel."""

import functools
import os

import numpy as np
from scipy.special import roots_legendre

from .errors import StippleError
from .halftone import (
    MAX_BANDWIDTH,
    Problem,
    check_count,
    check_epsilon,
    check_integer,
    check_memory,
    check_threads,
    default_threads,
    hexagonal_spacing,
    peak_ratio,
    run,
)
from .io.images import check_grid, load_density, load_input
from .kernels import NearKernel, chord_profile, sphere_kernel
from .manifolds import Sphere
from .nearfield import NearField, SpherePairs
from .objective import Discrepancy, SumObjective
from .torus import cell_factor
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


class CellMap:
    """A density constant on the cells of an equirectangular map.

    Row 0 is the band next to the north pole (``theta in [0, pi/H]``); column ``j`` covers longitudes
    ``[lon0 + 360 j / W, lon0 + 360 (j+1) / W)`` degrees east.
    """

    def __init__(self, values, lon0=0.0):
        self.values = check_grid(np.asarray(values, dtype=np.float64), "map")
        if np.any(self.values < 0):
            raise StippleError("map: density must be non-negative")
        self.lon0 = float(lon0)
        rows, columns = self.values.shape
        edges = np.cos(np.linspace(0, np.pi, rows + 1))
        self.cell_areas = np.outer(edges[:-1] - edges[1:], np.full(columns, 2 * np.pi / columns))
        if not np.sum(self.values * self.cell_areas) > 0:
            raise StippleError("map: density is zero everywhere; there is nothing to place dots on")

    @property
    def mean(self):
        """Area-weighted mean of the density (its mass over 4 pi)."""
        return float(np.sum(self.values * self.cell_areas) / (4 * np.pi))

    def coefficients(self, lmax, threads=1):
        """Exact ``w_nm = int w conj(Y_nm)`` of the cell-constant map, ``0 <= m <= n <= lmax``.

        Exact in longitude (row FFT times the cell factor); in colatitude each band is integrated by
        Gauss-Legendre in theta with enough nodes for the trigonometric polynomial ``Y_nm sin(theta)``,
        then ``ducc0.sht.leg2alm`` sums the Legendre functions over all nodes.
        """
        import ducc0

        rows, columns = self.values.shape
        orders = np.arange(lmax + 1)
        row_spectra = np.fft.fft(self.values, axis=1)[:, orders % columns]
        phase = np.exp(-1j * orders * np.radians(self.lon0)) * cell_factor(orders, columns) * 2 * np.pi / columns
        nodes_per_band = int(np.ceil((lmax + 2) * np.pi / rows / 2)) + 10
        nodes, weights = roots_legendre(nodes_per_band)
        half = np.pi / rows / 2
        theta = (np.arange(rows)[:, None] * 2 + 1) * half + half * nodes[None, :]
        ring_weights = half * weights[None, :] * np.sin(theta)
        leg = (ring_weights[:, :, None] * (row_spectra * phase)[:, None, :]).reshape(1, -1, lmax + 1)
        return ducc0.sht.leg2alm(leg=leg, lmax=lmax, theta=theta.ravel(), spin=0, nthreads=threads)[0]

    def cell_map(self):
        """The map itself (densities share this interface for sampling and cap masses)."""
        return self

    def at(self, longitude, latitude):
        """The density at ``(longitude, latitude)`` degrees (arrays of one shape): the value of their cell."""
        rows, columns = self.values.shape
        row = np.clip(np.floor((90.0 - np.asarray(latitude)) / 180.0 * rows), 0, rows - 1).astype(int)
        column = np.floor(np.mod(np.asarray(longitude) - self.lon0, 360.0) / 360.0 * columns).astype(int)
        return self.values[row, np.minimum(column, columns - 1)]

    def centres_and_masses(self):
        """Unit vectors of the cell centres and the density's mass in each cell (flattened)."""
        rows, columns = self.values.shape
        theta = (np.arange(rows) + 0.5) * np.pi / rows
        phi = np.radians(self.lon0) + (np.arange(columns) + 0.5) * 2 * np.pi / columns
        centres = unit_vectors(np.cos(theta)[:, None] + 0 * phi, phi[None, :] + 0 * theta[:, None])
        return centres.reshape(-1, 3), (self.values * self.cell_areas).ravel()

    def sample(self, rng, count):
        """I.i.d. points from the cell-constant density: a cell by its mass, then uniform in area."""
        rows, columns = self.values.shape
        mass = np.cumsum((self.values * self.cell_areas).ravel())
        cells = np.minimum(np.searchsorted(mass, rng.random(count) * mass[-1], side="right"), mass.size - 1)
        row, column = np.divmod(cells, columns)
        top, bottom = np.cos(row * np.pi / rows), np.cos((row + 1) * np.pi / rows)
        z = bottom + (top - bottom) * rng.random(count)
        phi = np.radians(self.lon0) + 2 * np.pi * (column + rng.random(count)) / columns
        return unit_vectors(z, phi)


class AnalyticDensity:
    """A smooth density given as a function of unit vectors ``(M, 3) -> (M,)``."""

    def __init__(self, function, name="density"):
        self.function = function
        self.name = name

    def _grid(self, lmax):
        """Gauss-Legendre rings and equispaced longitudes, exact for degree ``2 * lmax``."""
        rings = 2 * lmax + 2
        theta = np.arccos(-roots_legendre(rings)[0])
        phi = 2 * np.pi * np.arange(2 * rings) / (2 * rings)
        points = unit_vectors(np.cos(theta)[:, None] + 0 * phi, phi[None, :] + 0 * theta[:, None])
        return theta, phi, self.function(points.reshape(-1, 3)).reshape(len(theta), len(phi))

    @property
    def mean(self):
        return float(self.cell_map().mean)

    def coefficients(self, lmax, threads=1):
        """``w_nm`` by Gauss-Legendre quadrature on a grid of degree ``2 lmax`` (at least 512)."""
        import ducc0

        theta, phi, values = self._grid(max(lmax, 256))
        if not np.all(np.isfinite(values)) or np.any(values < 0):
            raise StippleError(f"{self.name}: density must be finite and non-negative")
        weighted = values * _gauss_weights(len(theta))[:, None] * 2 * np.pi / len(phi)
        return ducc0.sht.adjoint_synthesis_2d(map=weighted[None], lmax=lmax, spin=0, geometry="GL", nthreads=threads)[0]

    @functools.cached_property
    def _cells(self):
        rows = 360
        latitudes = (np.arange(rows) + 0.5) * np.pi / rows
        longitudes = (np.arange(2 * rows) + 0.5) * np.pi / rows
        z, phi = np.cos(latitudes)[:, None] + 0 * longitudes, longitudes[None, :] + 0 * latitudes[:, None]
        return CellMap(self.function(unit_vectors(z.ravel(), phi.ravel())).reshape(rows, 2 * rows))

    def cell_map(self):
        """The density on a 0.5° cell grid (for sampling starts and cap masses), evaluated once."""
        return self._cells

    def sample(self, rng, count):
        """Approximately i.i.d. from the density (its values on a 0.5° grid), good for a start."""
        return self.cell_map().sample(rng, count)


def _gauss_weights(rings):
    return roots_legendre(rings)[1]


class UniformDensity(AnalyticDensity):
    """``w ≡ 1``: numerical spherical designs."""

    def __init__(self):
        super().__init__(lambda points: np.ones(len(points)), "uniform")

    @property
    def mean(self):
        return 1.0

    def coefficients(self, lmax, threads=1):
        coeffs = np.zeros((lmax + 1) * (lmax + 2) // 2, dtype=np.complex128)
        coeffs[0] = np.sqrt(4 * np.pi)
        return coeffs

    def sample(self, rng, count):
        return Sphere().random(rng, count)


def unit_vectors(z, phi):
    """Unit vectors from height ``z = cos(theta)`` and longitude ``phi`` (radians)."""
    radius = np.sqrt(np.clip(1 - z**2, 0, None))
    return np.stack([radius * np.cos(phi), radius * np.sin(phi), z], axis=-1)


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
):
    """The halftoning problem of ``weights`` (see ``halftone_sphere``) with ``n_points`` dots on S²."""
    density = as_density(weights, lon0)
    n_points = check_count(n_points)
    bandwidth = check_degree(default_bandwidth(n_points, density) if bandwidth is None else bandwidth)
    kernel = default_kernel(density, n_points) if kernel is None else kernel
    if epsilon is None:
        epsilon = DESIGN_EPSILON if kernel.startswith("distance+design") else DEFAULT_EPSILON
    near_field = kernel.startswith("distance") if near_field is None else bool(near_field)
    if near_field and not kernel.startswith("distance"):
        raise StippleError(f"the near field needs the distance kernel, not {kernel!r}")
    # ducc0's general SHTs work on a doubled-sphere grid of about (2N)^2 complex values.
    check_memory(16 * 16 * (bandwidth + 1) ** 2 + 60 * 8 * n_points, f"M={n_points}, N={bandwidth}")
    threads = default_threads() if threads is None else check_threads(threads)
    epsilon = check_epsilon(epsilon)
    target = density.coefficients(bandwidth, threads)
    degrees, _ = alm_degrees_orders(bandwidth)
    kernel_coeffs = sphere_kernel(kernel, degrees)
    fourier = SphereFourier(bandwidth, epsilon, threads)
    weight = target[0].real * np.sqrt(4 * np.pi) / n_points
    if near_field:
        near = NearKernel(chord_profile, min(NEAR_FIELD_REACH / bandwidth, 0.5))
        cross_kernel = near.sphere_coefficients(bandwidth)[degrees]
        discrepancy = Discrepancy(fourier, kernel_coeffs - cross_kernel, target, weight, cross_kernel=cross_kernel)
        objective = SumObjective(discrepancy, NearField(near, weight, SpherePairs(), threads=threads))
    else:
        objective = discrepancy = Discrepancy(fourier, kernel_coeffs, target, weight)
    return Problem(
        domain="sphere",
        manifold=Sphere(),
        objective=objective,
        discrepancy=discrepancy,
        n_points=n_points,
        bandwidth=bandwidth,
        sample=density.sample,
        settings={
            "domain": "sphere",
            "points": n_points,
            "bandwidth": bandwidth,
            "kernel": kernel,
            "near_field": near_field,
            "hessian": "gauss-newton",
        },
    )


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
        weights, n_points, bandwidth, lon0=lon0, kernel=kernel, threads=threads, epsilon=epsilon, near_field=near_field
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
    """The density of a map (``-`` is stdin), a built-in name (``builtin:NAME``) or, with ``uniform``, w ≡ 1."""
    if uniform:
        if source is not None:
            raise StippleError("give either MAP or --uniform, not both")
        return BUILTINS["uniform"]
    if source is None:
        raise StippleError("missing MAP (a .npy map, an image, builtin:NAME) or --uniform")
    if source.startswith("builtin:"):
        name = source.partition(":")[2]
        if name not in BUILTINS:
            raise StippleError(f"unknown built-in density {name!r}; choose from {', '.join(BUILTINS)}")
        return BUILTINS[name]
    return CellMap(load_input(source, invert=invert, gamma=gamma, value_range=value_range), lon0)
