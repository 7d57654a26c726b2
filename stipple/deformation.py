"""Smooth deformations of a point set on T²: CG over the coefficients of a bandlimited displacement field.

Every dot moves by the same smooth field, ``x_i = p_i + u(p_i)`` with ``u(x) = Re sum_n a_n e^{2 pi i n.x}`` over
the modes ``|n_j| <= N_j / 2`` of a low bandwidth, and CG chooses the coefficients ``a`` (one complex grid per
axis) to lower an objective of the moved points. The map ``a -> x`` is linear, so the objective's gradient in
``a`` is the adjoint transform of its gradient at the dots and its Hessian form that of the displacements.

A warm video frame (``stipple.video``) is corrected this way with its whole objective, the near field included:
the steps fix the picture's low and middle frequencies, which a viewer sees, without stirring the dots' local
arrangement (the high frequencies, which the plain ``E_N`` of a low bandwidth cannot see and disturbs).
"""

import numpy as np

from .nufft import make_nufft
from .optimize import minimize
from .torus_spectrum import scaled_bandwidths
from .transforms import torus_modes

# The displacement field's transforms are small: ducc0 on one thread, whatever the objective's backend (the pool's
# overhead at every call would exceed the work).
THREADS = 1
EPSILON = 1e-9


class Deformation:
    """The linear map from a displacement field's coefficients to moved points: build once on the ``origin``
    points, then evaluate for many coefficient arrays.

    Parameters
    ----------
    origin : numpy.ndarray
        ``(M, 2)`` points in unit coordinates, where the field is evaluated.
    bandwidths : tuple of int
        Even per-axis bandwidths ``(N1, N2)`` of the field.
    """

    def __init__(self, origin, bandwidths):
        self.origin = np.asarray(origin, dtype=np.float64)
        self.shape = (2,) + tuple(n + 1 for n in bandwidths)
        self._nufft = make_nufft("ducc0", self.shape[1:], EPSILON, THREADS)
        self._nufft.set_points(self.origin)

    def zero(self):
        """The coefficients of no displacement, as a flat real vector (CG's "points")."""
        return np.zeros(2 * int(np.prod(self.shape)))

    def displacement(self, coeffs):
        """``u(p_i)``, ``(M, 2)``, for the flat real vector ``coeffs`` (interleaved real and imaginary parts)."""
        return self._nufft.type2(self._complex(coeffs)).real.T

    def points(self, coeffs):
        """The moved points ``p_i + u(p_i)``, wrapped into [0, 1)²."""
        return np.mod(self.origin + self.displacement(coeffs), 1.0)

    def pullback(self, covector):
        """The differential in the coefficients of a differential ``(M, 2)`` at the dots: the adjoint of
        ``displacement`` (``sum_i g_i e^{-2 pi i n.p_i}``), as a flat real vector."""
        coeffs = self._nufft.type1(np.ascontiguousarray(covector.T, dtype=np.complex128))
        return coeffs.view(np.float64).reshape(-1)

    def _complex(self, coeffs):
        return np.ascontiguousarray(coeffs).view(np.complex128).reshape(self.shape)


class DeformationSpace:
    """The flat space of a field's coefficients, for CG, with the metric ``scale_j² / (1 + |xi|²)`` on mode ``n``
    of axis ``j`` (``xi = (n1 / scale_x, n2 / scale_y)``, the physical frequency).

    The objective's curvature falls with the frequency of a deformation (the discrepancy's kernel decays as
    ``|xi|^-3`` while the density's change grows as ``|xi|``), so the flat metric's Newton steps were too short
    for the finer deformations: with this one, 10 iterations left a fade 1.5 dB below a cold run at sigma 4 px,
    against 2.9 dB with the flat metric (docs/video.md).
    """

    def __init__(self, scale, deformation):
        scale = np.asarray(scale, dtype=float)
        n1, n2 = torus_modes(deformation.shape[1:])
        per_mode = 1 / (1 + (n1 / scale[0]) ** 2 + (n2 / scale[1]) ** 2)
        per_axis = np.stack([side**2 * per_mode for side in scale])
        # Interleaved real and imaginary parts share their mode's factor.
        self._metric = np.repeat(per_axis.reshape(-1), 2)

    def inner(self, coeffs, u, v):
        return float(np.dot(u * self._metric, v))

    def norm(self, coeffs, v):
        return np.sqrt(self.inner(coeffs, v, v))

    def riesz(self, coeffs, covector):
        return covector / self._metric

    def retract(self, coeffs, v):
        return coeffs + v

    def transport(self, coeffs, v, w):
        return w

    def canonical(self, coeffs):
        return coeffs


class DeformedObjective:
    """``objective`` of the points that ``deformation`` makes of a field's coefficients."""

    def __init__(self, objective, deformation):
        self.objective = objective
        self.deformation = deformation

    def set_points(self, coeffs):
        self.objective.set_points(self.deformation.points(coeffs))

    def energy(self):
        return self.objective.energy()

    def gradient(self):
        return self.deformation.pullback(self.objective.gradient())

    def hessian_gram(self, vectors):
        return self.objective.hessian_gram([self.deformation.displacement(v) for v in vectors])


def deform(objective, scale, points, bandwidth, iterations, *, time_limit=None, callback=None):
    """Move ``points`` by the smooth field of ``bandwidth`` (per axis in proportion to ``scale``) that CG finds
    in ``iterations`` steps on ``objective``.

    Parameters
    ----------
    objective : object
        The objective of ``(M, 2)`` points (``set_points``, ``energy``, ``gradient``, ``hessian_gram``).
    scale : array_like
        The torus's physical side lengths (``stipple.manifolds.Torus.scale``).
    points : numpy.ndarray
        ``(M, 2)`` starting points in unit coordinates.
    bandwidth : int
        The field's bandwidth along the longer side (even, at least 2).
    iterations : int
    time_limit, callback :
        See ``stipple.optimize.minimize`` (``callback`` sees CG's states in the coefficients).

    Returns
    -------
    (numpy.ndarray, OptimizeResult)
        The moved points and CG's result in the coefficients.
    """
    deformation = Deformation(points, scaled_bandwidths(bandwidth, np.asarray(scale, dtype=float)))
    result = minimize(
        DeformedObjective(objective, deformation),
        DeformationSpace(scale, deformation),
        deformation.zero(),
        tol=0.0,
        max_iterations=iterations,
        time_limit=time_limit,
        callback=callback,
    )
    return deformation.points(result.points), result
