"""Raw 2-D NUFFT backends on the unit torus with one interface: ``set_points`` (a plan at the points), ``type1``
(values at the points to the centred mode grid of shape ``(N1+1, N2+1)``), ``type2`` (its adjoint, the mode grid to
the points), each for a batch. ``make_nufft`` picks one; every CPU path gives the same bits for a given thread count.
``stipple.transforms`` builds the Fourier systems of the objectives on them.
"""

import numpy as np

from .parallel import thread_pool
from .precision import precision

# "cufinufft" runs on an NVIDIA GPU (``stipple.gpu``, the ``gpu`` extra).
BACKENDS = ("ducc0", "finufft", "cufinufft")


class Ducc0Nufft:
    """2-D NUFFT on [0, 1)² through ``ducc0.nufft`` (centred grid, periodicity 1)."""

    name = "ducc0"

    def __init__(self, shape, epsilon, threads):
        import ducc0

        self._ducc0 = ducc0
        self.shape = tuple(shape)
        self.epsilon = epsilon
        self.threads = threads
        self.counts = {"type1": 0, "type2": 0, "set_points": 0}
        self._real, self._complex = precision(epsilon)
        self._plan = None

    def set_points(self, points):
        self._plan = self._ducc0.nufft.plan(
            nu2u=True,
            coord=np.ascontiguousarray(points, dtype=self._real),
            grid_shape=self.shape,
            epsilon=self.epsilon,
            nthreads=self.threads,
            periodicity=1.0,
            fft_order=False,
        )
        self.counts["set_points"] += 1

    def type1(self, values):
        """``out[b, n] = sum_i values[b, i] exp(-2 pi i n . p_i)`` for a batch ``(B, M)``."""
        return self.type1_native(values).astype(np.complex128, copy=False)

    def type1_native(self, values):
        """``type1`` in the transform's own precision (complex64 in single precision)."""
        self.counts["type1"] += len(values)
        out = np.empty((len(values),) + self.shape, dtype=self._complex)
        return self._plan.nu2u(forward=True, points=np.ascontiguousarray(values, dtype=self._complex), out=out)

    def type2(self, coeffs):
        """``out[b, i] = sum_n coeffs[b, n] exp(+2 pi i n . p_i)`` for a batch ``(B, N1+1, N2+1)``."""
        self.counts["type2"] += len(coeffs)
        out = self._plan.u2nu(forward=False, grid=np.ascontiguousarray(coeffs, dtype=self._complex))
        return out.astype(np.complex128, copy=False)


class FinufftNufft:
    """The same transforms through ``finufft``.

    Upsampling factor 1.25 with ``epsilon / 3`` (the fast choice measured here) unless ``epsilon``
    is below what that factor reaches, then 2.
    """

    name = "finufft"

    def __init__(self, shape, epsilon, threads):
        import finufft

        self.shape = tuple(shape)
        self.epsilon = epsilon
        self.threads = threads
        self.counts = {"type1": 0, "type2": 0, "set_points": 0}
        upsampfac = 1.25 if epsilon >= 1e-10 else 2.0
        self._real, self._complex = precision(epsilon)
        self._plan = finufft.Plan(
            1,
            self.shape,
            eps=max(epsilon / 3, 1e-14),
            isign=-1,
            nthreads=threads,
            upsampfac=upsampfac,
            dtype=np.dtype(self._complex).name,
        )

    def set_points(self, points):
        self._points = 2 * np.pi * np.ascontiguousarray(points.T, dtype=self._real)
        self._plan.setpts(self._points[0], self._points[1])
        self.counts["set_points"] += 1

    def type1(self, values):
        return self.type1_native(values).astype(np.complex128, copy=False)

    def type1_native(self, values):
        self.counts["type1"] += len(values)
        return np.stack([self._plan.execute(np.ascontiguousarray(v, dtype=self._complex)) for v in values])

    def type2(self, coeffs):
        self.counts["type2"] += len(coeffs)
        out = [self._plan.execute_adjoint(np.ascontiguousarray(c, dtype=self._complex)) for c in coeffs]
        return np.stack(out).astype(np.complex128, copy=False)


class ResidueSplitNufft:
    """Multi-threaded transforms that give the same bits on every run with the same thread count.

    Both libraries' multi-threaded type-1 transforms add contributions in scheduling order. Here, with ``T``
    threads, the modes ``n1 = T m + r`` of each residue class ``r`` are one single-threaded type-1 transform of
    the points ``(T x mod 1, y)`` with values ``v_i exp(-2 pi i o_r x_i)``, because
    ``exp(-2 pi i n.p) = exp(-2 pi i o_r x) exp(-2 pi i (m', n2).(T x, y))`` with ``n1 = T m' + o_r`` and
    ``m'`` in the class grid's own centred range. The classes run at once and fill disjoint rows; together they
    cost one transform's FFT and ``T`` spreads. Type-2 transforms interpolate each point on its own and are
    deterministic with the backend's threads; their plan is made at the first type-2 transform after
    ``set_points`` (a grid used for type-1 transforms only never makes it).
    """

    def __init__(self, backend_class, shape, epsilon, threads):
        self.name = backend_class.name
        self.shape = tuple(shape)
        self.epsilon = epsilon
        self.threads = threads
        self.counts = {"type1": 0, "type2": 0, "set_points": 0}
        self._full = backend_class(shape, epsilon, threads)
        self._classes = []
        half = self.shape[0] // 2
        for residue in range(threads):
            low, high = -((half + residue) // threads), (half - residue) // threads
            size = high - low + 1
            offset = threads * (low + size // 2) + residue
            first_row = threads * low + residue + half
            self._classes.append((offset, first_row, backend_class((size, self.shape[1]), epsilon, 1)))
        self._phases = None
        self._full_points = None

    def set_points(self, points):
        self._full_points = np.array(points, dtype=np.float64)  # a copy: the caller may reuse its array
        folded = np.array(points, dtype=np.float64)
        folded[:, 0] = np.mod(self.threads * folded[:, 0], 1.0)

        def one_class(residue):
            offset, _, nufft = self._classes[residue]
            nufft.set_points(folded)
            # The class of offset 0 (one of them for any thread count) needs no phase.
            return None if offset == 0 else np.exp(-2j * np.pi * offset * points[:, 0])

        self._phases = list(thread_pool(self.threads).map(one_class, range(self.threads)))
        self.counts["set_points"] += 1

    def type1(self, values):
        self.counts["type1"] += len(values)
        out = np.empty((len(values),) + self.shape, dtype=np.complex128)

        def one_class(residue):
            # One task per class: a plan is never used by two threads at once (ducc0's plans are not thread-safe).
            _, first_row, nufft = self._classes[residue]
            phase = self._phases[residue]
            # Cast into the strided rows directly: no grid-sized double-precision copy per class.
            out[:, first_row :: self.threads] = nufft.type1_native(values if phase is None else values * phase)

        list(thread_pool(self.threads).map(one_class, range(self.threads)))
        return out

    def type2(self, coeffs):
        self.counts["type2"] += len(coeffs)
        if self._full_points is not None:
            self._full.set_points(self._full_points)
            self._full_points = None
        return self._full.type2(coeffs)


# Below this many rows per thread, the split costs more than it saves and one thread does all.
MIN_ROWS_PER_THREAD = 32


def make_nufft(backend, shape, epsilon, threads):
    """The NUFFT backend called ``backend`` (one of ``BACKENDS``), bit-reproducible for a given ``threads`` on the CPU
    (the GPU's agree to rounding)."""
    classes = {"ducc0": Ducc0Nufft, "finufft": FinufftNufft}
    if backend == "cufinufft":
        from .gpu import CufinufftNufft

        return CufinufftNufft(shape, epsilon, threads)
    if backend not in classes:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, not {backend!r}")
    if threads > 1 and shape[0] >= MIN_ROWS_PER_THREAD * threads:
        return ResidueSplitNufft(classes[backend], shape, epsilon, threads)
    return classes[backend](shape, epsilon, 1)
