"""The bandlimited quadrature error ``E_N`` as an objective on point sets."""

import numpy as np

from .errors import StippleError
from .parallel import map_blocks, map_terms, sum_blocks


class Discrepancy:
    """``E(p) = sum_l mult_l k_l |F_l(p)|^2`` with ``F_l = lam * sum_i conj(psi_l(p_i)) - w_l``.

    With a near-field split (``cross_kernel`` given) ``kernel`` is the smooth part ``k^R`` and ``cross_kernel`` the
    short-range part ``k^near`` of the full kernel ``k = k^R + k^near``. The near part's point-point sum is
    ``NearField``'s; only its point-density cross term is left here:

        E = sum_l mult_l ( k^R_l |F_l|^2 - k^near_l (|w_l|^2 + 2 Re conj(F_l) w_l) ),

    which is ``sum_l mult_l k^near_l ( |F_l|^2 - lam^2 |c_l|^2 )`` and makes ``E + E_near`` the untruncated
    discrepancy up to the tails of ``k^R`` and of the density's spectrum beyond the band.

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
    cross_kernel : numpy.ndarray, optional
        Coefficients ``k^near_l`` of the near-field part, same layout (default: no split).

    Notes
    -----
    All derivatives are differentials in the point coordinates of ``fourier`` (covectors); the manifold
    turns them into tangent vectors.
    """

    def __init__(self, fourier, kernel, target, weight, hessian="gauss-newton", cross_kernel=None):
        if hessian not in ("gauss-newton", "full"):
            raise StippleError(f"hessian must be 'gauss-newton' or 'full', not {hessian!r}")
        if hessian == "full" and not hasattr(fourier, "hessian_synthesis"):
            raise StippleError("hessian='full' is only available on the torus")
        self.fourier = fourier
        # Mode-grid arithmetic runs on the transforms' threads, in row blocks (``stipple.parallel``).
        self.threads = getattr(fourier, "threads", 1)
        self.kernel = kernel
        # Weights in sums over the whole spectrum; on the torus (multiplicity 1) the kernel itself, not a copy:
        # at M = 10^6 every mode-grid array is 112-224 MB.
        self.energy_weights = _times_multiplicity(kernel, fourier.multiplicity)
        self._pair_weights = np.repeat(np.broadcast_to(self.energy_weights, np.shape(target)).ravel(), 2)
        self._jacobian_weights = weight * kernel
        self.target = target
        self.weight = weight
        self.hessian = hessian
        # Without a split the near part is the scalar 0 (no mode-grid arrays of zeros).
        self.cross_kernel = 0.0 if cross_kernel is None else cross_kernel
        self._has_cross = bool(np.any(self.cross_kernel))
        self._cross_pull = self.cross_kernel * target if self._has_cross else 0.0
        if self._has_cross:
            # -sum mult k^near (|w|^2 + 2 Re conj(F) w): a constant and one real dot product with F per evaluation.
            weighted_pull = _times_multiplicity(self._cross_pull, fourier.multiplicity)
            self._cross_constant = -float(np.sum(weighted_pull.conj() * target).real)
            self._cross_dot = _real_view(np.ascontiguousarray(weighted_pull, dtype=np.complex128))
        self._residual = None

    def set_points(self, points):
        """Move to ``points`` and compute the residual ``F`` there."""
        self.fourier.set_points(points)
        residual = self.fourier.analysis()
        map_blocks(self.threads, self._form_residual, residual, self.target)
        self._residual = residual

    def _form_residual(self, sums, target):
        """``F = lam c - w`` in place of the sums ``c`` (one block)."""
        sums *= self.weight
        sums -= target

    @property
    def residual(self):
        """``F_l`` at the current points (read-only; None before the first ``set_points``)."""
        if self._residual is None:
            return None
        view = self._residual.view()
        view.flags.writeable = False
        return view

    def energy(self):
        residual = _real_view(self._residual)
        quadratic = sum_blocks(self.threads, _weighted_square, self._pair_weights, residual)
        if not self._has_cross:
            return quadratic
        cross = -2 * sum_blocks(self.threads, _dot, self._cross_dot, residual)
        return quadratic + self._cross_constant + cross

    def bandlimited_energy(self):
        """The paper's ``E_N = sum_l mult_l k_l |F_l|^2`` with the whole kernel ``k = k^R + k^near``."""
        return float(np.sum(self.bandlimited_weights * np.abs(self._residual) ** 2))

    @property
    def bandlimited_weights(self):
        """``mult_l (k^R_l + k^near_l)``: the whole kernel's weights (made when asked, not kept)."""
        return _times_multiplicity(self.kernel + self.cross_kernel, self.fourier.multiplicity)

    def _synthesis_coeffs(self):
        """``k^R F - k^near w``: the coefficients whose gradient synthesis is ``dE/dp / (2 lam)``."""
        coeffs = np.empty_like(self._residual)
        if self._has_cross:
            map_blocks(self.threads, _product_minus, coeffs, self.kernel, self._residual, self._cross_pull)
        else:
            map_blocks(self.threads, np.multiply, self.kernel, self._residual, coeffs)
        return coeffs

    def gradient(self):
        """``dE/dp_i = 2 lam Re sum_l (k^R_l F_l - k^near_l w_l) grad psi_l(p_i)``."""
        return 2 * self.weight * self.fourier.gradient_synthesis([self._synthesis_coeffs()])[0]

    def hessian_gram(self, vectors):
        """Matrix of the Hessian's bilinear form ``G[a, b] = v_a . H v_b`` on the given fields.

        The Gauss-Newton part is ``2 lam^2 Re sum_l mult_l k_l conj(J v_a)_l (J v_b)_l``, so no synthesis
        transform is needed: CG uses the Hessian only through such forms.
        """
        gram = 2 * self.weight**2 * self.fourier.jacobian_gram(vectors, self.energy_weights)
        count = len(vectors)
        if self.hessian == "full":
            curvature = 2 * self.weight * self.fourier.hessian_synthesis(self._synthesis_coeffs())
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
            curvature = 2 * self.weight * self.fourier.hessian_synthesis(self._synthesis_coeffs())
            products = [hv + np.einsum("mij,mj->mi", curvature, v) for hv, v in zip(products, vectors, strict=True)]
        return products


def _weighted_square(weights, values):
    return np.einsum("i,i,i->", weights, values, values)


def _dot(first, second):
    return np.einsum("i,i->", first, second)


def _product_minus(out, first, second, subtracted):
    """``out = first * second - subtracted`` (one block)."""
    np.multiply(first, second, out=out)
    out -= subtracted


def _times_multiplicity(values, multiplicity):
    """``values * multiplicity``, or ``values`` itself where the multiplicity is the scalar 1."""
    if np.ndim(multiplicity) == 0 and multiplicity == 1:
        return values
    return values * multiplicity


def _real_view(coeffs):
    """Interleaved real and imaginary parts of a contiguous complex array, without a copy."""
    return np.ascontiguousarray(coeffs).view(np.float64).reshape(-1)


class SumObjective:
    """The sum of objectives at the same points (the transform part and the near field): what CG drives.

    With ``concurrent`` the terms are evaluated at once, each on a thread of its own (``stipple.parallel.map_terms``;
    the terms then share the threads between them, see ``stipple.torus.torus_problem``), and their results are
    added in term order: the same bits as one after the other.
    """

    def __init__(self, *terms, concurrent=False):
        self.terms = terms
        self.concurrent = concurrent

    def set_points(self, points):
        self._each(lambda term: term.set_points(points))

    def energy(self):
        return sum(term.energy() for term in self.terms)

    def gradient(self):
        return sum(self._each(lambda term: term.gradient()))

    def hessian_gram(self, vectors):
        return sum(self._each(lambda term: term.hessian_gram(vectors)))

    def hessian_vectors(self, vectors):
        per_term = self._each(lambda term: term.hessian_vectors(vectors))
        return [sum(products) for products in zip(*per_term, strict=True)]

    def _each(self, function):
        if self.concurrent:
            return map_terms(function, self.terms)
        return [function(term) for term in self.terms]
