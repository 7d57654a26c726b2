"""The disc measure's objective and manifold: separable disc factors, ``DiscDiscrepancy``, ``DiscTorus``.

The maths, conventions and choices are in ``stipple.discs`` (the public entry: ``optimise_discs``).
"""

import numpy as np
from numpy.polynomial import chebyshev
from scipy.special import j0, j1

from ..errors import StippleError
from ..torus import DEFAULT_EPSILON
from ..torus_spectrum import radial_on_modes
from ..transforms import torus_modes

# The factors cover radii up to HEADROOM times the largest radius seen; rebuilt when a radius grows beyond.
HEADROOM = 1.5
# |xi| samples on [0, |xi|_max] at which the factors are fitted and checked; u samples at which they are checked.
FREQUENCY_SAMPLES = 512
SIZE_SAMPLES = 257
MAX_NODES = 96


def disc_transform(rho):
    """``phi(rho) = 2 J1(2 pi rho) / (2 pi rho)``: a disc's Fourier transform over its area, ``phi(0) = 1``.

    ``rho = |xi| r`` is the physical frequency times the radius: the disc of radius ``r`` around ``p`` has the
    transform ``pi r^2 phi(|xi| r) e^{-2 pi i xi.p}``.
    """
    z = 2 * np.pi * np.asarray(rho, dtype=float)
    safe = np.where(z == 0, 1.0, z)
    return np.where(z == 0, 1.0, 2 * j1(safe) / safe)


def disc_factor(frequency, u):
    """``pi u phi(|xi| sqrt(u))``: a disc of squared radius ``u`` seen at frequency ``|xi|`` (outer product)."""
    u = np.asarray(u, dtype=float)
    return np.pi * u * disc_transform(np.multiply.outer(frequency, np.sqrt(u)))


class DiscFactors:
    """Separable ``pi u phi(|xi| sqrt(u)) ~ sum_q beta_q(|xi|) alpha_q(u)`` on ``[0, max_frequency] x [0, U]``.

    ``alpha_q`` are polynomials in ``u`` (Chebyshev interpolation at ``P`` first-kind nodes, the fewest that
    reach the tolerance) spanning the leading right singular vectors of the node values over ``|xi|``; ``beta_q``
    are exact sums of ``disc_factor`` at the nodes, evaluated on any frequency.

    Parameters
    ----------
    max_frequency : float
        Largest physical frequency ``|xi|`` in the band, > 0.
    max_radius : float
        Largest radius ``sqrt(U)`` covered, > 0.
    tolerance : float
        Largest error allowed, relative to the area ``pi U``, checked on a grid of ``|xi|`` and ``u``.
    """

    def __init__(self, max_frequency, max_radius, tolerance):
        if not max_frequency > 0 or not max_radius > 0 or not np.isfinite(max_frequency * max_radius):
            raise StippleError(f"max_frequency and max_radius must be positive, not {max_frequency}, {max_radius}")
        self.max_u = float(max_radius) ** 2
        frequency = np.linspace(0.0, max_frequency, FREQUENCY_SAMPLES)
        checks = np.linspace(-1.0, 1.0, SIZE_SAMPLES)
        exact = disc_factor(frequency, self.max_u * (1 + checks) / 2) / (np.pi * self.max_u)
        for count in range(4, MAX_NODES + 1, 2):
            nodes = np.cos(np.pi * (np.arange(count) + 0.5) / count)
            values = disc_factor(frequency, self.max_u * (1 + nodes) / 2) / (np.pi * self.max_u)
            inverse = np.linalg.inv(chebyshev.chebvander(nodes, count - 1))
            interpolate = chebyshev.chebvander(checks, count - 1) @ inverse
            if np.max(np.abs(values @ interpolate.T - exact)) <= tolerance / 4:
                break
        else:
            raise StippleError(
                f"discs of radius {max_radius:.3g} at frequency {max_frequency:.3g} need more than {MAX_NODES} "
                "interpolation nodes: use smaller discs or a lower bandwidth"
            )
        vectors = np.linalg.svd(values, full_matrices=False)[2].T
        for rank in range(1, count + 1):
            projector = vectors[:, :rank] @ vectors[:, :rank].T
            if np.max(np.abs(values @ projector @ interpolate.T - exact)) <= tolerance:
                break
        self.nodes = self.max_u * (1 + nodes) / 2
        self.vectors = vectors[:, :rank]
        self.coefficients = inverse @ self.vectors
        self.derivative = chebyshev.chebder(self.coefficients) * (2 / self.max_u)

    @property
    def rank(self):
        """The number ``R`` of separable terms (transforms per field)."""
        return self.vectors.shape[1]

    def sizes(self, u):
        """``alpha_q(u_i)`` and ``u_i alpha_q'(u_i)`` as two ``(M, R)`` arrays."""
        t = 2 * np.asarray(u, dtype=float) / self.max_u - 1
        basis = chebyshev.chebvander(t, len(self.coefficients) - 1)
        return basis @ self.coefficients, u[:, None] * (basis[:, :-1] @ self.derivative)

    def radial(self, frequency):
        """``beta_q(|xi|)``, shape ``frequency.shape + (R,)``."""
        return disc_factor(frequency, self.nodes) @ self.vectors


class DiscDiscrepancy:
    """``E(p, s) = sum_n K_n |mu_n - w_n|^2`` of discs at ``p_i`` with areas ``a_i = exp(s_i)`` (see the module).

    Points are ``(M, 3)`` arrays ``(x, y, s)``: unit coordinates on the torus and the log area in physical units.
    The interface is ``stipple.objective.Discrepancy``'s: ``set_points``, ``energy``, ``gradient`` (the
    differential, a covector), ``hessian_gram`` and ``hessian_vectors`` (Gauss-Newton).

    Parameters
    ----------
    nufft : Ducc0Nufft, FinufftNufft or ResidueSplitNufft
        Transforms on the centred ``(N1+1, N2+1)`` mode grid (``stipple.nufft.make_nufft``).
    kernel : numpy.ndarray
        ``K_n`` on that grid, ``K_0`` included (the mass term).
    target : numpy.ndarray
        ``w_n`` of the ink density on that grid (``stipple.torus_spectrum.image_coefficients``).
    scale : array_like
        Physical side lengths ``(W/L, H/L)`` of the torus.
    epsilon : float
        Accuracy of the separable disc factors, relative to the largest disc's area.
    """

    def __init__(self, nufft, kernel, target, scale, epsilon=DEFAULT_EPSILON):
        self.nufft = nufft
        self.kernel = kernel
        self.target = target
        self.scale = np.asarray(scale, dtype=float)
        self.area = float(np.prod(self.scale))
        self.epsilon = epsilon
        n1, n2 = torus_modes(nufft.shape)
        self.bandwidths = (nufft.shape[0] - 1, nufft.shape[1] - 1)
        self.max_frequency = float(np.hypot(*(np.array(self.bandwidths) / 2 / self.scale)))
        self._shift = 2j * np.pi * (n1 + 1j * n2)
        self._unpack = (-1j * np.pi * (n1 - 1j * n2), -1j * np.pi * (n1 + 1j * n2))
        self.factors = None
        self._residual = None

    def _build(self, max_radius):
        """Separable factors for radii up to ``max_radius`` and their mode grids."""
        self.factors = DiscFactors(self.max_frequency, max_radius, self.epsilon)
        betas = radial_on_modes(self.factors.radial, self.bandwidths, self.scale)
        self._betas = np.ascontiguousarray(np.moveaxis(betas, -1, 0))
        padded = np.concatenate([self._betas, np.zeros((self._betas.shape[0] % 2,) + self._betas.shape[1:])])
        # Pairs (q, q') of real data packed into one complex transform: gamma = (beta_q - i beta_q') / 2.
        self._gammas = (padded[0::2] - 1j * padded[1::2]) / 2

    def set_points(self, points):
        """Move to ``points`` (``(M, 3)``: x, y, log area) and compute the residual ``mu - w`` there."""
        points = np.asarray(points, dtype=np.float64)
        u = np.exp(points[:, 2]) / np.pi
        largest = float(np.max(u))
        if self.factors is None or largest > self.factors.max_u:
            self._build(HEADROOM * np.sqrt(largest))
        self._alpha, self._size_alpha = self.factors.sizes(u)
        self.nufft.set_points(np.mod(points[:, :2], 1.0))
        self._coefficients = self._hermitian(self._gammas, self.nufft.type1(_pairs(self._alpha.T))) / self.area
        self._residual = self._coefficients - self.target

    @staticmethod
    def _hermitian(gammas, sums):
        """``Y + conj(Y)_{-n}`` with ``Y = sum_p gamma_p Z_p``: the real data's terms, unpacked and summed."""
        combined = np.einsum("pij,pij->ij", gammas, sums)
        return combined + combined[::-1, ::-1].conj()

    @property
    def coefficients(self):
        """``mu_n`` of the discs at the current points (read-only)."""
        return _read_only(self._coefficients)

    @property
    def residual(self):
        """``mu_n - w_n`` at the current points (read-only)."""
        return _read_only(self._residual)

    def energy(self):
        return float(np.sum(self.kernel * (self._residual.real**2 + self._residual.imag**2)))

    def gradient(self):
        """``(dE/dx, dE/dy, dE/ds)`` per dot, ``(M, 3)``; x, y in unit coordinates."""
        return self._pullback(self.kernel * self._residual)

    def _pullback(self, coeffs):
        """``2 Re J^H c`` for Hermitian mode coefficients ``c``: ``(M, 3)``."""
        rank = self.factors.rank
        packed = np.concatenate([self._betas * (self._shift * coeffs), 2 * self._gammas.conj() * coeffs])
        values = self.nufft.type2(packed)
        motion, sizes = values[:rank], _unpair(values[rank:], rank)
        out = np.empty((self._alpha.shape[0], 3))
        out[:, 0] = np.einsum("iq,qi->i", self._alpha, motion.real)
        out[:, 1] = np.einsum("iq,qi->i", self._alpha, motion.imag)
        out[:, 2] = np.einsum("iq,qi->i", self._size_alpha, sizes)
        return (2 / self.area) * out

    def jacobian(self, vectors):
        """``J v = sum_i (dmu/dp_i . v_p,i + dmu/ds_i v_s,i)`` for each ``(M, 3)`` field: mode arrays."""
        rank = self.factors.rank
        batches = []
        for v in vectors:
            batches.append(self._alpha.T * (v[:, 0] + 1j * v[:, 1]))
            batches.append(_pairs((self._size_alpha * v[:, 2:3]).T))
        sums = self.nufft.type1(np.concatenate(batches))
        step = rank + len(self._gammas)
        products = []
        for index in range(len(vectors)):
            block = sums[index * step : (index + 1) * step]
            moved = np.einsum("qij,qij->ij", self._betas, block[:rank])
            product = self._unpack[0] * moved + self._unpack[1] * moved[::-1, ::-1].conj()
            product += self._hermitian(self._gammas, block[rank:])
            products.append(product / self.area)
        return products

    def hessian_gram(self, vectors):
        """``G[a, b] = 2 Re sum_n K_n conj(J v_a)_n (J v_b)_n``: the Gauss-Newton Hessian's form."""
        jacobians = self.jacobian(vectors)
        count = len(vectors)
        gram = np.empty((count, count))
        for a in range(count):
            for b in range(a, count):
                value = 2 * np.sum(self.kernel * (jacobians[a].conj() * jacobians[b]).real)
                gram[a, b] = gram[b, a] = value
        return gram

    def hessian_vectors(self, vectors):
        """Gauss-Newton ``2 Re J^H K J v`` for each field (covectors, ``(M, 3)``)."""
        return [self._pullback(self.kernel * jv) for jv in self.jacobian(vectors)]


def _pairs(rows):
    """Real rows ``(R, M)`` packed two to a complex row: ``(ceil(R/2), M)``."""
    if len(rows) % 2:
        rows = np.concatenate([rows, np.zeros((1,) + rows.shape[1:])])
    return np.ascontiguousarray(rows[0::2] + 1j * rows[1::2])


def _unpair(values, rank):
    """The real rows packed by ``_pairs`` back as ``(R, M)``."""
    return np.stack([values.real, values.imag], axis=1).reshape(-1, values.shape[-1])[:rank]


def _read_only(array):
    if array is None:
        return None
    view = array.view()
    view.flags.writeable = False
    return view


class DiscTorus:
    """Positions on the flat torus times log areas: points ``(M, 3)`` = ``(x, y, s)``, ``s = log(pi r^2)``.

    The metric is ``sum_i (scale_x^2 dx_i dx'_i + scale_y^2 dy_i dy'_i + size_metric ds_i ds'_i)``: physical
    lengths on the torus and a constant weight on the log areas (``balanced_size_metric``). Retraction wraps the
    positions and adds to the log areas; transport is the identity.

    Parameters
    ----------
    scale : array_like
        Physical side lengths ``(W/L, H/L)``.
    size_metric : float
        Weight of ``ds^2`` against a squared physical length, > 0.
    reference_size : float
        Log area that ``random`` gives every dot.
    fixed_sizes : bool
        Keep the sizes where they are: ``riesz`` drops the ``s`` component, so CG moves positions only.
    """

    dimension = 3

    def __init__(self, scale=(1.0, 1.0), size_metric=1.0, reference_size=0.0, fixed_sizes=False):
        if not size_metric > 0 or not np.isfinite(size_metric):
            raise StippleError(f"size_metric must be a positive number, not {size_metric!r}")
        self.scale = np.asarray(scale, dtype=float)
        self.size_metric = float(size_metric)
        self.reference_size = float(reference_size)
        self.fixed_sizes = bool(fixed_sizes)
        self._metric = np.append(self.scale**2, self.size_metric)

    def inner(self, points, u, v):
        return float(np.einsum("ij,ij->j", u, v) @ self._metric)

    def norm(self, points, v):
        return np.sqrt(self.inner(points, v, v))

    def riesz(self, points, covector):
        vector = covector / self._metric
        if self.fixed_sizes:
            vector[:, 2] = 0.0
        return vector

    def retract(self, points, v):
        moved = points + v
        moved[:, :2] = np.mod(moved[:, :2], 1.0)
        return moved

    def transport(self, points, v, w):
        return w

    def canonical(self, points):
        points = np.array(points, dtype=np.float64)
        points[:, :2] = np.mod(points[:, :2], 1.0)
        return points

    def random(self, rng, count):
        return np.column_stack([rng.random((count, 2)), np.full(count, self.reference_size)])


def balanced_size_metric(kernel, scale, radius):
    """The weight of ``ds^2`` that equalises the Gauss-Newton Hessian's diagonal in ``s`` and in a position.

    For one disc of radius ``radius`` both diagonal entries carry ``a^2``, so their ratio does not depend on the
    disc's size beyond ``phi`` and ``J0``: ``sum_n K_n J0(2 pi |xi| r)^2 / sum_n K_n 2 pi^2 |xi|^2 phi(|xi| r)^2``
    (the denominator is the mean over the two axes of ``sum K (2 pi xi_x)^2 phi^2``).
    """
    n1, n2 = torus_modes((kernel.shape[0], kernel.shape[1]))
    frequency = np.hypot(n1 / scale[0], n2 / scale[1])
    sizes = np.sum(kernel * j0(2 * np.pi * frequency * radius) ** 2)
    moves = np.sum(kernel * 2 * np.pi**2 * frequency**2 * disc_transform(frequency * radius) ** 2)
    return float(sizes / moves)
