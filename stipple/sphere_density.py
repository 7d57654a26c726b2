"""Densities on the sphere: cell maps (equirectangular, exact coefficients), analytic functions, the uniform
density, and their values at points."""

import functools

import numpy as np
from scipy.special import roots_legendre

from .errors import StippleError
from .io.images import check_grid
from .manifolds import Sphere
from .sampling import block_sums, stratified_cells
from .torus_spectrum import cell_factor


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

    def refined(self, factor):
        """The same map with every cell cut into ``factor x factor`` cells (equal in colatitude and longitude)."""
        return CellMap(np.repeat(np.repeat(self.values, factor, axis=0), factor, axis=1), self.lon0)

    def centres_and_masses(self, block=1):
        """Unit vectors of the cell centres and the density's mass in each cell (flattened); with ``block``, of
        blocks of ``block x block`` cells (smaller along the last rows and columns), each centred in colatitude
        and longitude."""
        rows, columns = self.values.shape
        masses, (centre_rows, centre_columns) = block_sums(self.values * self.cell_areas, block)
        theta = centre_rows * np.pi / rows
        phi = np.radians(self.lon0) + centre_columns * 2 * np.pi / columns
        centres = unit_vectors(np.cos(theta)[:, None] + 0 * phi, phi[None, :] + 0 * theta[:, None])
        return centres.reshape(-1, 3), masses.ravel()

    def sample(self, rng, count):
        """I.i.d. points from the cell-constant density: a cell by its mass, then uniform in area."""
        mass = np.cumsum((self.values * self.cell_areas).ravel())
        cells = np.minimum(np.searchsorted(mass, rng.random(count) * mass[-1], side="right"), mass.size - 1)
        return self._in_cells(cells, rng)

    def stratified(self, rng, count):
        """Points stratified over the cells' masses along a Hilbert curve through the map
        (``stipple.sampling.stratified_cells``), each uniform in area within its cell."""
        return self._in_cells(stratified_cells(self.values * self.cell_areas, rng, count), rng)

    def _in_cells(self, cells, rng):
        """A point uniform in area in each of ``cells`` (flat indices)."""
        rows, columns = self.values.shape
        count = len(cells)
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

    def values_at(self, points):
        """The function at ``points`` ``(K, 3)``, checked: one finite, non-negative real number per point (a
        function returning a number, or complex values, failed deep inside with numpy's or ducc0's error)."""
        values = np.asarray(self.function(points))
        if values.shape != (len(points),) or values.dtype.kind not in "biuf":
            raise StippleError(
                f"{self.name}: the density function must return one real number per point, an array of shape "
                f"({len(points)},), not {values.dtype} of shape {values.shape}"
            )
        values = values.astype(np.float64)
        if not np.all(np.isfinite(values)) or np.any(values < 0):
            raise StippleError(f"{self.name}: density must be finite and non-negative")
        return values

    def _grid(self, lmax):
        """Gauss-Legendre rings and equispaced longitudes, exact for degree ``2 * lmax``."""
        rings = 2 * lmax + 2
        theta = np.arccos(-roots_legendre(rings)[0])
        phi = 2 * np.pi * np.arange(2 * rings) / (2 * rings)
        points = unit_vectors(np.cos(theta)[:, None] + 0 * phi, phi[None, :] + 0 * theta[:, None])
        return theta, phi, self.values_at(points.reshape(-1, 3)).reshape(len(theta), len(phi))

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
        return CellMap(self.values_at(unit_vectors(z.ravel(), phi.ravel())).reshape(rows, 2 * rows))

    def cell_map(self):
        """The density on a 0.5° cell grid (for sampling starts and cap masses), evaluated once."""
        return self._cells

    def sample(self, rng, count):
        """Approximately i.i.d. from the density (its values on a 0.5° grid), good for a start."""
        return self.cell_map().sample(rng, count)

    def stratified(self, rng, count):
        """Stratified over the density's values on a 0.5° grid (``CellMap.stratified``)."""
        return self.cell_map().stratified(rng, count)


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


def density_at(density, points):
    """Value of a sphere density at unit vectors ``points``.

    Parameters
    ----------
    density : CellMap or AnalyticDensity or UniformDensity
        A map is constant on its cells (column ``j`` starts at ``lon0 + 360 j / W`` degrees east, row 0 at
        the north pole); an analytic density is its function; anything else is read through ``cell_map()``.
    points : numpy.ndarray
        ``(M, 3)`` unit vectors.

    Returns
    -------
    numpy.ndarray
        ``(M,)`` density values.
    """
    if hasattr(density, "function"):
        return density.values_at(points)
    if not hasattr(density, "values"):
        return density_at(density.cell_map(), points)
    rows, columns = density.values.shape
    theta = np.arccos(np.clip(points[:, 2], -1, 1))
    phi = np.mod(np.arctan2(points[:, 1], points[:, 0]) - np.radians(density.lon0), 2 * np.pi)
    row = np.minimum((theta / np.pi * rows).astype(int), rows - 1)
    column = np.minimum((phi / (2 * np.pi) * columns).astype(int), columns - 1)
    return density.values[row, column]


def local_density(density, points):
    """Dots per steradian that ``density`` asks for at each of ``points`` (``M w(p) / int w``)."""
    return len(points) * density_at(density, points) / (4 * np.pi * density.mean)


def unit_vectors(z, phi):
    """Unit vectors from height ``z = cos(theta)`` and longitude ``phi`` (radians)."""
    radius = np.sqrt(np.clip(1 - z**2, 0, None))
    return np.stack([radius * np.cos(phi), radius * np.sin(phi), z], axis=-1)
