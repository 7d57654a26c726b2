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
        Which Hessian ``hessian_vector`` applies; "full" needs ``fourier.hessian_synthesis``.

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
        self._jacobian_weights = weight * kernel
        self.target = target
        self.weight = weight
        self.hessian = hessian
        self._residual = None

    def set_points(self, points):
        """Move to ``points`` and compute the residual ``F`` there."""
        self.fourier.set_points(points)
        self._residual = self.weight * self.fourier.analysis() - self.target

    def energy(self):
        residual = self._residual
        return float(np.sum(self.energy_weights * (residual.real**2 + residual.imag**2)))

    def gradient(self):
        """``dE/dp_i = 2 lam Re sum_l k_l F_l grad psi_l(p_i)``."""
        return 2 * self.weight * self.fourier.gradient_synthesis([self.kernel * self._residual])[0]

    def hessian_gram(self, vectors):
        """Matrix of the Hessian's bilinear form ``G[a, b] = v_a . H v_b`` on the given fields.

        The Gauss-Newton part is ``2 Re sum_l mult_l k_l conj(J v_a)_l (J v_b)_l``, so no synthesis
        transform is needed: CG uses the Hessian only through such forms.
        """
        jacobians = [self.weight * jv for jv in self.fourier.gradient_analysis(vectors)]
        count = len(vectors)
        gram = np.empty((count, count))
        for a in range(count):
            for b in range(a, count):
                product = np.conj(jacobians[a]) * jacobians[b]
                gram[a, b] = gram[b, a] = 2 * np.sum(self.energy_weights * product.real)
        if self.hessian == "full":
            curvature = 2 * self.weight * self.fourier.hessian_synthesis(self.kernel * self._residual)
            for a in range(count):
                for b in range(a, count):
                    extra = np.einsum("mi,mij,mj->", vectors[a], curvature, vectors[b])
                    gram[a, b] += extra
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
