"""Fourier coefficients of the discrepancy kernels.

Both kernels are positive definite and band-limited by truncation: only the coefficients
``k_l`` for the modes in the band enter the energy ``E_N = sum_l k_l |F_l|^2``.
"""

import numpy as np
from scipy.special import j1, roots_legendre

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


def sphere_kernel(kernel, degrees):
    """Kernel coefficients by degree: ``"distance"`` (the paper's restricted distance kernel) or
    ``"sobolev:S"``, ``k_n = (1 + n(n+1))^-S`` (flatter: better conditioned, for numerical designs)."""
    if kernel == "distance":
        return distance_kernel(degrees)
    name, _, exponent = str(kernel).partition(":")
    try:
        smoothness = float(exponent)
    except ValueError:
        smoothness = None
    if name != "sobolev" or smoothness is None or not 0 <= smoothness <= 4:
        raise StippleError(f"kernel must be 'distance' or 'sobolev:S' with 0 <= S <= 4, not {kernel!r}")
    degrees = np.asarray(degrees, dtype=float)
    return np.where(degrees == 0, 0.0, (1 + degrees * (degrees + 1)) ** -smoothness)
