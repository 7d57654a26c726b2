"""The bandlimited quadrature error ``E_N`` as an objective on point sets."""

import numpy as np


class Discrepancy:
    """``E(p) = sum_l mult_l k_l |F_l(p)|^2`` with ``F_l = lam * sum_i conj(psi_l(p_i)) - w_l``.

    Parameters
    ----------
    fourier : TorusFourier or SphereFourier
        The transforms at the current points (``set_points`` is called by ``set_points`` here).
    kernel : numpy.ndarray
        Kernel coefficients ``k_l`` in the layout of ``fourier`` (``k_0 = 0``).
    target : numpy.ndarray
        Coefficients ``w_l = int w conj(psi_l)`` of the density, same layout.
    weight : float
        Quadrature weight ``lam = w_0 / M`` of every point.
    hessian : {"gauss-newton", "full"}
        Which Hessian ``hessian_gram`` and ``hessian_vectors`` use; "full" needs ``fourier.hessian_synthesis``.

    Notes
    -----
    All derivatives are differentials in the point coordinates of ``fourier`` (covectors); the manifold
    turns them into tangent vectors.
    """

    def __init__(self, fourier, kernel, target, weight, hessian="gauss-newton"):
        if hessian not in ("gauss-newton", "full"):
            raise ValueError(f"hessian must be 'gauss-newton' or 'full', not {hessian!r}")
        if hessian == "full" and not hasattr(fourier, "hessian_synthesis"):
            raise ValueError("hessian='full' is only available on the torus")
        self.fourier = fourier
        self.kernel = kernel
        self.energy_weights = kernel * fourier.multiplicity
        self._pair_weights = np.repeat(np.broadcast_to(self.energy_weights, np.shape(target)).ravel(), 2)
        self._jacobian_weights = weight * kernel
        self.target = target
        self.weight = weight
        self.hessian = hessian
        self._residual = None

    def set_points(self, points):
        """Move to ``points`` and compute the residual ``F`` there."""
        self.fourier.set_points(points)
        residual = self.fourier.analysis()
        residual *= self.weight
        residual -= self.target
        self._residual = residual

    def energy(self):
        residual = _real_view(self._residual)
        return float(np.einsum("i,i,i->", self._pair_weights, residual, residual))

    def gradient(self):
        """``dE/dp_i = 2 lam Re sum_l k_l F_l grad psi_l(p_i)``."""
        return 2 * self.weight * self.fourier.gradient_synthesis([self.kernel * self._residual])[0]

    def hessian_gram(self, vectors):
        """Matrix of the Hessian's bilinear form ``G[a, b] = v_a . H v_b`` on the given fields.

        The Gauss-Newton part is ``2 lam^2 Re sum_l mult_l k_l conj(J v_a)_l (J v_b)_l``, so no synthesis
        transform is needed: CG uses the Hessian only through such forms.
        """
        gram = 2 * self.weight**2 * self.fourier.jacobian_gram(vectors, self.energy_weights)
        count = len(vectors)
        if self.hessian == "full":
            curvature = 2 * self.weight * self.fourier.hessian_synthesis(self.kernel * self._residual)
            for a in range(count):
                for b in range(a, count):
                    gram[a, b] += np.einsum("mi,mij,mj->", vectors[a], curvature, vectors[b])
                    gram[b, a] = gram[a, b]
        return gram

    def hessian_vectors(self, vectors):
        """Hessian (Gauss-Newton ``2 J^H K J``, or full) applied to each field in ``vectors``."""
        coeffs = self.fourier.gradient_analysis(vectors)
        for jacobian in coeffs:
            jacobian *= self._jacobian_weights
        products = [2 * self.weight * hv for hv in self.fourier.gradient_synthesis(coeffs)]
        if self.hessian == "full":
            curvature = 2 * self.weight * self.fourier.hessian_synthesis(self.kernel * self._residual)
            products = [hv + np.einsum("mij,mj->mi", curvature, v) for hv, v in zip(products, vectors, strict=True)]
        return products


def _real_view(coeffs):
    """Interleaved real and imaginary parts of a contiguous complex array, without a copy."""
    return np.ascontiguousarray(coeffs).view(np.float64).reshape(-1)
