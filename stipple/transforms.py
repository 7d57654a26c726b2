"""Fast transforms between point sets and Fourier coefficients.

Two layers:

* ``stipple.nufft``: raw 2-D type-1/type-2 NUFFT backends on the unit torus with one interface
  (``set_points``, ``type1``, ``type2``), centred mode grids of shape ``(N1+1, N2+1)``.
* ``TorusFourier`` / ``SphereFourier``: the three operations the discrepancy objective needs, for
  any domain with an orthonormal Fourier basis ``psi_l``::

      analysis()               c_l = sum_i conj(psi_l(p_i))
      gradient_synthesis(a)    v_i = Re sum_l a_l grad psi_l(p_i)          (tangent vectors)
      gradient_analysis(v)     b_l = sum_i conj(grad psi_l(p_i)) . v_i     (its adjoint)

  ``multiplicity`` weights each stored coefficient in sums over the whole (real-symmetric) spectrum.
"""

import functools

import numpy as np

from .nufft import make_nufft
from .parallel import map_blocks, sum_blocks
from .precision import precision


def centred_modes(bandwidth):
    """The integer frequencies ``-N/2 .. N/2`` of one axis of a centred mode array (``N + 1`` of them)."""
    return np.arange(-(bandwidth // 2), bandwidth // 2 + 1)


def torus_modes(shape):
    """Integer frequency grids ``(n1, n2)`` of a centred mode array of ``shape = (N1+1, N2+1)``."""
    axes = [centred_modes(size - 1).astype(float) for size in shape]
    return np.meshgrid(*axes, indexing="ij")


class TorusFourier:
    """Fourier system ``psi_n(u) = exp(2 pi i n . u)`` on the unit torus, modes ``|n_j| <= N_j/2``.

    Real point data are packed two to a complex transform: the ``x`` and ``y`` components of a
    gradient are the real and imaginary parts of one type-2 transform, and a tangent field is
    analysed by one type-1 transform of ``v_x + i v_y``.

    ``nufft`` (the whole mode grid) makes the derivatives' transforms (``gradient_synthesis``, ``gradient_analysis``,
    ``jacobian_gram``, ``hessian_synthesis``) at its own accuracy; ``analysis``, whose sums the residual subtracts
    from the target, has its own plans at ``analysis_epsilon`` (default: the same) on ``analysis_threads`` (default:
    ``nufft``'s), which also do the mode-grid arithmetic. A derivative only steers CG and sizes its step, so it may
    be coarser than the residual (``stipple.torus.DERIVATIVE_EPSILON``).
    """

    def __init__(self, nufft, analysis_epsilon=None, analysis_threads=None):
        self.nufft = nufft
        # Mode-grid arithmetic runs on the transforms' threads, in row blocks (``stipple.parallel``).
        self.threads = nufft.threads if analysis_threads is None else analysis_threads
        self.epsilon = nufft.epsilon if analysis_epsilon is None else analysis_epsilon
        # ``analysis`` sums real values, so c_-n = conj(c_n): it transforms the rows n1 >= 0 only, on an odd grid
        # of at least N1/2 + 1 rows whose centre row is n1 = half_offset, and mirrors them.
        half_rows = nufft.shape[0] // 2 + 1
        half_rows += 1 - half_rows % 2
        self.half_nufft = make_nufft(nufft.name, (half_rows, nufft.shape[1]), self.epsilon, self.threads)
        self._half_offset = half_rows // 2
        self._half_phase = None
        self.modes = torus_modes(nufft.shape)
        self.multiplicity = 1.0
        n1, n2 = self.modes
        self._synthesis_factor = 2j * np.pi * (n1 + 1j * n2)
        self._gram_weights = None

    @functools.cached_property
    def _analysis_factors(self):
        """``-pi i (n1 -+ i n2)``, for ``gradient_analysis`` only (CG needs only its forms): made when first asked,
        two complex mode grids that would otherwise take 450 MB at M = 10^6 from the start."""
        n1, n2 = self.modes
        return -1j * np.pi * (n1 - 1j * n2), -1j * np.pi * (n1 + 1j * n2)

    @property
    def counts(self):
        """Transforms made so far on both grids: ``type1``, ``type2``, ``set_points`` (plans)."""
        return {key: self.nufft.counts[key] + self.half_nufft.counts[key] for key in self.nufft.counts}

    def set_points(self, points):
        self.nufft.set_points(points)
        self.half_nufft.set_points(points)
        self._half_phase = np.exp(-2j * np.pi * self._half_offset * points[:, 0])[None]

    def analysis(self):
        """``c_n = sum_i exp(-2 pi i n.p_i)``: the rows ``n1 >= 0`` transformed, the others their mirror image."""
        half = self.half_nufft.type1(self._half_phase)[0]
        rows = self.nufft.shape[0] // 2
        sums = np.empty(self.nufft.shape, dtype=np.complex128)
        map_blocks(self.threads, np.copyto, sums[rows:], half[: rows + 1])
        map_blocks(self.threads, np.conjugate, half[rows:0:-1, ::-1], sums[:rows])
        return sums

    def gradient_synthesis(self, coeffs):
        """Tangent fields ``Re sum_n a_n (2 pi i n) e^{2 pi i n.u_i}`` for a list of Hermitian arrays."""
        # Products made in double precision and stored in the transform's own (the values its conversion gave):
        # no grid-sized double-precision array, no second pass to convert it.
        packed = np.empty((len(coeffs),) + self.nufft.shape, dtype=precision(self.nufft.epsilon)[1])
        for out, a in zip(packed, coeffs, strict=True):
            map_blocks(self.threads, np.multiply, self._synthesis_factor, a, out)
        values = self.nufft.type2(packed)
        return [np.stack([v.real, v.imag], axis=1) for v in values]

    def _analyse_packed(self, vectors):
        """Type-1 transforms of ``v_x + i v_y`` for each real ``(M, 2)`` field."""
        return self.nufft.type1(np.stack([v[:, 0] + 1j * v[:, 1] for v in vectors]))

    def gradient_analysis(self, vectors):
        """``sum_i (-2 pi i n . v_i) e^{-2 pi i n.u_i}`` for a list of real ``(M, 2)`` fields."""
        packed = self._analyse_packed(vectors)
        # T(v_x) = (T(z)_n + conj T(z)_-n) / 2 and T(v_y) = (T(z)_n - conj T(z)_-n) / 2i, z = v_x + i v_y.
        mirrored = packed[:, ::-1, ::-1].conj()
        mirrored *= self._analysis_factors[1]
        packed *= self._analysis_factors[0]
        packed += mirrored
        return list(packed)

    def jacobian_gram(self, vectors, weights):
        """``G[a, b] = Re sum_n weights_n conj(J v_a)_n (J v_b)_n`` with ``J`` = ``gradient_analysis``.

        Works on the packed transforms ``T = T(v_x + i v_y)`` without unpacking: with ``A_n = -pi i (n1 - i n2)``,
        ``J_n = A_n T_n + conj(A_-n T_-n)``, so for weights symmetric in ``n``
        ``G = 2 Re sum w |A|^2 conj(Ta) Tb + 2 Re sum w pi^2 (n1 - i n2)^2 Ta_n Tb_-n``.
        """
        if self._gram_weights is None or self._gram_weights[0] is not weights:
            n1, n2 = self.modes
            self._gram_weights = (
                weights,
                2 * weights * np.pi**2 * (n1**2 + n2**2),
                2 * weights * np.pi**2 * (n1 - 1j * n2) ** 2,
            )
        _, same, mirrored = self._gram_weights
        packed = self._analyse_packed(vectors)
        count = len(vectors)
        gram = np.empty((count, count))
        for a in range(count):
            for b in range(a, count):
                gram[a, b] = gram[b, a] = sum_blocks(
                    self.threads, _packed_gram_terms, same, mirrored, packed[a], packed[b], packed[b, ::-1, ::-1]
                )
        return gram

    def hessian_synthesis(self, coeffs):
        """Second derivatives ``Re sum_n a_n (-4 pi^2 n n^T) e^{2 pi i n.u_i}`` as an ``(M, 2, 2)`` array."""
        n1, n2 = self.modes
        scaled = -4 * np.pi**2 * coeffs
        first, second = self.nufft.type2(np.stack([scaled * n1 * (n1 + 1j * n2), scaled * n2 * n2]))
        h11, h12, h22 = first.real, first.imag, second.real
        return np.stack([np.stack([h11, h12], axis=1), np.stack([h12, h22], axis=1)], axis=1)


def _packed_gram_terms(same, mirrored, first, second, second_mirrored):
    """One block of ``jacobian_gram``'s sums: ``sum same Re(conj(Ta) Tb) + Re sum mirrored Ta Tb_-n``."""
    direct = np.einsum("ij,ij,ij->", same, first.real, second.real)
    direct += np.einsum("ij,ij,ij->", same, first.imag, second.imag)
    return direct + np.einsum("ij,ij,ij->", mirrored, first, second_mirrored).real


def alm_size(lmax):
    """Number of stored coefficients ``a_nm``, ``0 <= m <= n <= lmax`` (healpy/ducc0 layout)."""
    return (lmax + 1) * (lmax + 2) // 2


def alm_degrees_orders(lmax):
    """Degree ``n`` and order ``m`` of every stored coefficient, index ``m(2L+1-m)/2 + n``."""
    orders = np.concatenate([np.full(lmax + 1 - m, m) for m in range(lmax + 1)])
    degrees = np.concatenate([np.arange(m, lmax + 1) for m in range(lmax + 1)])
    return degrees, orders


def spherical_angles(points):
    """Colatitude ``theta`` in [0, pi] and longitude ``phi`` in [0, 2 pi) of unit vectors ``(M, 3)``."""
    theta = np.arccos(np.clip(points[:, 2], -1.0, 1.0))
    phi = np.mod(np.arctan2(points[:, 1], points[:, 0]), 2 * np.pi)
    return theta, phi


def spherical_frame(theta, phi):
    """Unit tangent vectors ``e_theta`` and ``e_phi`` (each ``(M, 3)``) at the given angles."""
    cos_t, sin_t, cos_p, sin_p = np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    e_theta = np.stack([cos_t * cos_p, cos_t * sin_p, -sin_t], axis=1)
    e_phi = np.stack([-sin_p, cos_p, np.zeros_like(phi)], axis=1)
    return e_theta, e_phi


class SphereFourier:
    """Orthonormal spherical harmonics ``Y_nm``, ``n <= lmax``, through ``ducc0.sht`` general transforms.

    Coefficients are stored for ``m >= 0`` only; a real field is ``sum a_n0 Y_n0 + 2 Re sum_{m>0} a_nm Y_nm``,
    hence ``multiplicity`` 1 for ``m = 0`` and 2 for ``m > 0``. Tangent vectors are ``(M, 3)`` arrays in R³,
    converted to (e_theta, e_phi) components only here.

    Syntheses run on ``threads``, adjoints on ``adjoint_threads`` (default: the same). ducc0's adjoint with
    several threads adds the points' contributions in a scheduling-dependent order (two runs differ in the last
    digits) and its synthesis does not: one adjoint thread gives the same bits every time.

    The derivatives' transforms (``gradient_synthesis``, ``gradient_analysis``, ``jacobian_gram``) run at
    ``derivative_epsilon`` (default: ``epsilon``), in single precision where it allows
    (``stipple.precision.precision``), as the torus's do; ``analysis``, whose sums the residual subtracts from
    the target, keeps ``epsilon``.
    """

    def __init__(self, lmax, epsilon, threads, adjoint_threads=None, derivative_epsilon=None):
        import ducc0

        self._sht = ducc0.sht
        self.lmax = lmax
        self.epsilon = epsilon
        self.derivative_epsilon = epsilon if derivative_epsilon is None else derivative_epsilon
        self._real, self._complex = precision(self.derivative_epsilon)
        self.threads = threads
        self.adjoint_threads = threads if adjoint_threads is None else adjoint_threads
        self.multiplicity = np.where(alm_degrees_orders(lmax)[1] == 0, 1.0, 2.0)
        self.counts = {"synthesis": 0, "adjoint": 0, "set_points": 0}

    def _options(self, adjoint=False, derivative=False):
        threads = self.adjoint_threads if adjoint else self.threads
        epsilon = self.derivative_epsilon if derivative else self.epsilon
        return dict(lmax=self.lmax, loc=self._loc, epsilon=epsilon, nthreads=threads)

    def set_points(self, points):
        theta, phi = spherical_angles(points)
        self._loc = np.stack([theta, phi], axis=1)
        self._frame = spherical_frame(theta, phi)
        self._ones = np.ones((1, len(points)))
        self.counts["set_points"] += 1

    def analysis(self):
        self.counts["adjoint"] += 1
        return self._sht.adjoint_synthesis_general(map=self._ones, spin=0, **self._options(adjoint=True))[0]

    def gradient_synthesis(self, coeffs):
        e_theta, e_phi = self._frame
        fields = []
        for alm in coeffs:
            self.counts["synthesis"] += 1
            alm = alm.astype(self._complex, copy=False)[None]
            v_theta, v_phi = self._sht.synthesis_general(
                alm=alm, spin=1, mode="DERIV1", **self._options(derivative=True)
            )
            fields.append(v_theta[:, None] * e_theta + v_phi[:, None] * e_phi)
        return fields

    def jacobian_gram(self, vectors, weights):
        """``G[a, b] = Re sum_l weights_l conj(J v_a)_l (J v_b)_l`` with ``J`` = ``gradient_analysis``."""
        jacobians = [np.ascontiguousarray(jv).view(np.float64) for jv in self.gradient_analysis(vectors)]
        pair_weights = np.repeat(weights, 2)
        count = len(vectors)
        gram = np.empty((count, count))
        for a in range(count):
            for b in range(a, count):
                gram[a, b] = gram[b, a] = np.einsum("i,i,i->", pair_weights, jacobians[a], jacobians[b])
        return gram

    def gradient_analysis(self, vectors):
        e_theta, e_phi = self._frame
        results = []
        for v in vectors:
            self.counts["adjoint"] += 1
            components = np.stack([np.sum(v * e_theta, axis=1), np.sum(v * e_phi, axis=1)]).astype(self._real)
            alm = self._sht.adjoint_synthesis_general(
                map=components, spin=1, mode="DERIV1", **self._options(adjoint=True, derivative=True)
            )
            results.append(alm[0].astype(np.complex128, copy=False))
        return results
