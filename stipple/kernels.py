"""Fourier coefficients of the discrepancy kernels.

Both kernels are positive definite and band-limited by truncation: only the coefficients
``k_l`` for the modes in the band enter the energy ``E_N = sum_l k_l |F_l|^2``.
"""

import numpy as np
from scipy.special import j0, j1, roots_legendre

from .errors import StippleError

_GAUSS_NODES, _GAUSS_WEIGHTS = roots_legendre(16)


def ball_kernel(radii):
    """Coefficients ``kB(r)`` of the discrepancy kernel of balls with radius <= 1/2 on T².

    ``kB(r) = (pi^2/160) 2F3(3/2, 5/2; 2, 3, 7/2; -pi^2 r^2)``, evaluated through the identity
    ``kB(r) = I(pi r) / (8 pi^3 r^5)`` with ``I(x) = int_0^x t^2 J1(t)^2 dt``, integrated by cumulative
    16-point Gauss-Legendre over the sorted distinct radii (sub-intervals no longer than pi).

    Parameters
    ----------
    radii : array_like
        Non-negative frequency radii ``|xi|``.

    Returns
    -------
    numpy.ndarray
        ``kB`` at each radius, same shape as ``radii``; ``kB(0) = pi^2/160``.
    """
    radii = np.asarray(radii, dtype=float)
    distinct, inverse = np.unique(radii, return_inverse=True)
    x = np.pi * distinct
    integral = np.cumsum(_integrate_t2_j1sq(np.concatenate(([0.0], x[:-1])), x))
    values = np.empty_like(distinct)
    positive = distinct > 0
    values[positive] = integral[positive] / (8 * np.pi**3 * distinct[positive] ** 5)
    values[~positive] = np.pi**2 / 160
    return values[inverse].reshape(radii.shape)


def _integrate_t2_j1sq(lower, upper):
    """``int_lower^upper t^2 J1(t)^2 dt`` for each pair, splitting into pieces no longer than pi."""
    pieces = np.maximum(1, np.ceil((upper - lower) / np.pi).astype(int))
    owner = np.repeat(np.arange(len(lower)), pieces)
    step = (upper - lower) / pieces
    index = np.arange(len(owner)) - np.repeat(np.cumsum(pieces) - pieces, pieces)
    a = lower[owner] + index * step[owner]
    half = 0.5 * step[owner]
    t = (a + half)[:, None] + half[:, None] * _GAUSS_NODES[None, :]
    piece_integrals = half * ((t * j1(t)) ** 2 @ _GAUSS_WEIGHTS)
    return np.bincount(owner, weights=piece_integrals, minlength=len(lower))


def distance_kernel(degrees):
    """Coefficients of the restricted distance kernel ``-||x - y||`` on S² by degree.

    ``k_n = 16 pi / ((2n+3)(2n+1)(2n-1))`` for ``n >= 1`` and ``k_0 = 0`` (the constant mode never
    contributes to the quadrature error).
    """
    n = np.asarray(degrees, dtype=float)
    values = 16 * np.pi / ((2 * n + 3) * (2 * n + 1) * (2 * n - 1))
    return np.where(n == 0, 0.0, values)


DESIGN_WEIGHT = 0.1


def sphere_kernel(kernel, degrees):
    """Kernel coefficients by degree.

    ``"distance"``: the paper's restricted distance kernel. ``"distance+design:T"``: the distance kernel plus
    ``0.1 (1 + n(n+1))^-1/2`` for ``1 <= n <= T``, which asks the points to integrate every harmonic up to degree
    ``T`` nearly exactly (a near-design) while the distance kernel keeps them spread (``--uniform``'s default).
    ``"sobolev:S"``: ``k_n = (1 + n(n+1))^-S`` (flatter: better conditioned, for numerical designs).
    """
    name, _, parameter = str(kernel).partition(":")
    if kernel == "distance":
        return distance_kernel(degrees)
    if name == "distance+design":
        return distance_kernel(degrees) + design_boost(degrees, _design_strength(kernel, parameter))
    try:
        smoothness = float(parameter)
    except ValueError:
        smoothness = None
    if name != "sobolev" or smoothness is None or not 0 <= smoothness <= 4:
        raise StippleError(
            f"kernel must be 'distance', 'distance+design:T' or 'sobolev:S' with 0 <= S <= 4, not {kernel!r}"
        )
    degrees = np.asarray(degrees, dtype=float)
    return np.where(degrees == 0, 0.0, (1 + degrees * (degrees + 1)) ** -smoothness)


def design_boost(degrees, strength):
    """``0.1 (1 + n(n+1))^-1/2`` for ``1 <= n <= strength``, else 0."""
    degrees = np.asarray(degrees, dtype=float)
    inside = (degrees >= 1) & (degrees <= strength)
    return np.where(inside, DESIGN_WEIGHT * (1 + degrees * (degrees + 1)) ** -0.5, 0.0)


def _design_strength(kernel, parameter):
    if not parameter.isdigit() or not 1 <= int(parameter) <= 8192:
        raise StippleError(f"kernel 'distance+design:T' needs a degree 1 <= T <= 8192, not {kernel!r}")
    return int(parameter)


# ---------------------------------------------------------------------------------------------------------------
# Near-field split: K = K_R + K_near with K_near supported in a small ball and K_R smooth enough for the transforms.


def _horner(x, coeffs):
    """``c0 + x (c1 + x (c2 + ...))`` in place on one array: the same products and sums, in the same order."""
    value = x * coeffs[-1]
    for coefficient in coeffs[-2:0:-1]:
        value += coefficient
        value *= x
    value += coeffs[0]
    return value


def ball_profile(distance, orders=5):
    """The ball-discrepancy kernel in space and its first four derivatives, as functions of the distance ``d``.

    ``kappa(d) = int_0^{1/2} |B(0, r) ∩ B(d e_1, r)| dr`` is the R² kernel whose Fourier transform is ``kB``
    (the lens area integrated over the radius); in closed form, for ``0 < d <= 1``,
    ``kappa = pi/24 - d sqrt(1-d²)/6 - arcsin(d)/12 + d³ asech(d)/12``, ``kappa' = -sqrt(1-d²)/4 + d² asech(d)/4``,
    ``kappa'' = d asech(d)/2``, ``kappa''' = (asech(d) - 1/sqrt(1-d²))/2``,
    ``kappa'''' = -(1/(d sqrt(1-d²)) + d/(1-d²)^(3/2))/2``. Only used for ``d`` well inside (0, 1).
    """
    d = np.asarray(distance, dtype=float)
    root = np.sqrt(1 - d * d)
    asech = np.arccosh(1 / d)
    square = d * d
    values = (
        np.pi / 24 - d * root / 6 - np.arcsin(d) / 12 + square * d * asech / 12,
        (square * asech - root) / 4,
        d * asech / 2,
    )
    if orders == 3:
        return values
    return values + ((asech - 1 / root) / 2, -(1 / (d * root) + d / root**3) / 2)


def chord_profile(distance, orders=5):
    """``-r`` and its derivatives: the distance kernel on S² as a function of the chordal distance ``r``."""
    r = np.asarray(distance, dtype=float)
    zero = np.zeros_like(r)
    return (-r, zero - 1.0, zero, zero, zero)[:orders]


class NearKernel:
    """``K_near(r) = g(r) - q(r)`` for ``r < radius`` and 0 beyond: the short range of a radial kernel ``g``.

    ``q(r) = sum_{k=0}^{4} a_k r^{2k}`` is the even polynomial that matches ``g`` and its first four derivatives
    at ``r = radius`` (a two-point Taylor regularisation, as in NFFT fast summation). So ``K_R = g - K_near``
    equals ``q`` inside the ball (smooth, even) and ``g`` outside, joined with four continuous derivatives; its
    Fourier coefficients decay fast beyond ``~1/radius`` and a bandwidth ``~4/radius`` represents it.

    Parameters
    ----------
    profile : callable
        ``profile(r, orders)``: the first ``orders`` of ``g`` and its derivatives up to the fourth at distances ``r``
        (``ball_profile`` or ``chord_profile``).
    radius : float
        Support radius, in the units of ``profile``'s argument.
    """

    ORDER = 4

    def __init__(self, profile, radius):
        self.profile = profile
        self.radius = float(radius)
        derivatives = np.array([float(value) for value in profile(self.radius)])
        powers = 2 * np.arange(self.ORDER + 1)
        system = np.array(
            [[_falling(power, order) * self.radius ** max(power - order, 0) for power in powers] for order in range(5)]
        )
        self.coeffs = np.linalg.solve(system, derivatives)

    def values(self, r):
        """``(K, K', K'')`` at distances ``r`` (zero at and beyond the radius; one-sided limits at 0)."""
        r = np.asarray(r, dtype=float)
        inside = r < self.radius
        return tuple(np.where(inside, value, 0.0) for value in self.values_inside(np.clip(r, 0.0, self.radius)))

    def values_inside(self, r):
        """``(K, K', K'')`` at distances ``0 <= r <= radius`` (one-sided limits at 0)."""
        g, g1, g2 = self.profile(np.maximum(r, 1e-300), orders=3)
        q, q1, q2 = self._polynomial(r)
        return g - q, g1 - q1, g2 - q2

    def pair_terms(self, distance, square=None):
        """``(sum of K, K'/r, K'')`` at distances ``0 < r < radius``: what the pair sums need (the polynomial's
        ``q'/r`` without a division). ``square``: ``distance * distance`` if the caller has it."""
        g, g1, g2 = self.profile(distance, orders=3)
        q, q1_over_r, q2 = self._polynomial_in_square(distance * distance if square is None else square)
        # K is a small difference of g and q (both near g(0)): summed after subtracting, not before. The
        # polynomial's arrays are this call's own, so the differences are taken in place.
        value_sum = float(np.sum(np.subtract(g, q, out=q)))
        force = np.subtract(np.divide(g1, distance), q1_over_r, out=q1_over_r)
        return value_sum, force, np.subtract(g2, q2, out=q2)

    def _polynomial(self, r):
        """``(q, q', q'')`` at distances ``r``."""
        value, first_over_r, second = self._polynomial_in_square(r * r)
        return value, r * first_over_r, second

    def _polynomial_in_square(self, square):
        """``(q, q'/r, q'')`` of the even polynomial, from ``r²``."""
        a = self.coeffs
        value = _horner(square, a)
        first_over_r = _horner(square, (2 * a[1], 4 * a[2], 6 * a[3], 8 * a[4]))
        second = _horner(square, (2 * a[1], 12 * a[2], 30 * a[3], 56 * a[4]))
        return value, first_over_r, second

    def plane_coefficients(self, frequencies):
        """2-D Fourier transform ``2 pi int_0^radius K_near(r) J0(2 pi rho r) r dr`` at radial frequencies ``rho``.

        ``K_near`` is compactly supported, so its transform is smooth in ``rho``: it is computed at Chebyshev
        nodes of ``[0, max rho]`` by composite Gauss-Legendre quadrature and interpolated (error ~1e-14).
        """
        frequencies = np.asarray(frequencies, dtype=float)
        top = max(float(frequencies.max(initial=0.0)), 1.0 / self.radius)
        degree = int(40 + 4 * top * self.radius)
        nodes = np.cos(np.pi * (np.arange(degree + 1) + 0.5) / (degree + 1))
        rho = (nodes + 1) * top / 2
        r, weights = _panels(self.radius, waves=top * self.radius)
        table = 2 * np.pi * (j0(2 * np.pi * rho[:, None] * r[None, :]) * (self.values(r)[0] * r * weights)).sum(axis=1)
        series = np.polynomial.chebyshev.Chebyshev.fit(nodes, table, degree)
        return series(2 * frequencies / top - 1)

    def sphere_coefficients(self, lmax):
        """``k_n = 2 pi int_{-1}^{1} K_near(|x - y|) P_n(t) dt``, ``t = x . y``, for ``n = 0..lmax``.

        With ``t = cos(theta)`` the chord is ``2 sin(theta/2)``; the integral runs over ``theta < 2 arcsin(radius/2)``.
        """
        theta_max = 2 * np.arcsin(min(self.radius / 2, 1.0))
        theta, weights = _panels(theta_max, waves=lmax * theta_max / np.pi)
        integrand = self.values(2 * np.sin(theta / 2))[0] * np.sin(theta) * weights
        t = np.cos(theta)
        coeffs = np.empty(lmax + 1)
        previous, current = np.ones_like(t), t.copy()
        coeffs[0] = integrand.sum()
        for n in range(1, lmax + 1):
            coeffs[n] = np.einsum("i,i->", integrand, current)
            previous, current = current, ((2 * n + 1) * t * current - n * previous) / (n + 1)
        return 2 * np.pi * coeffs


def _falling(power, order):
    """``power (power-1) ... (power-order+1)``: the factor of the ``order``-th derivative of ``r^power``."""
    result = 1.0
    for k in range(order):
        result *= power - k
    return result


def _panels(length, waves=0.0, nodes=24):
    """Composite Gauss-Legendre nodes and weights on ``[0, length]``: 16 panels graded towards 0 (where the kernels
    have their cusp), refined to at least one panel per wave of an integrand with ``waves`` oscillations."""
    graded = np.geomspace(1e-4, 1.0, 16)
    even = np.linspace(0.0, 1.0, int(np.ceil(waves)) + 2)
    edges = length * np.unique(np.concatenate([[0.0], graded, even]))
    x, w = roots_legendre(nodes)
    half = np.diff(edges)[:, None] / 2
    points = (edges[:-1, None] + half) + half * x[None, :]
    return points.ravel(), (half * w[None, :]).ravel()
