"""The torus transforms on an NVIDIA GPU through ``cufinufft`` (the ``gpu`` extra: cufinufft and CuPy).

``CufinufftNufft`` has the interface of ``stipple.nufft.Ducc0Nufft`` (``set_points``, ``type1``, ``type2`` on
NumPy arrays, centred ``(N1+1, N2+1)`` mode grids), so the objective and CG run unchanged on the CPU and only the
transforms move: each call copies its values to the GPU and its result back. The GPU's type-1 spreading adds with
atomic operations in no fixed order, so two runs with the same seed agree to rounding, not bit for bit. CuPy's
out-of-memory error is a ``MemoryError`` (the command line's "out of memory"); cufinufft's own failures become one
StippleError.
"""

import contextlib

import numpy as np

from .errors import StippleError
from .precision import precision

NEEDS_GPU = "needs cufinufft and CuPy on a machine with an NVIDIA GPU: pip install 'stipple[gpu]'"


def require_gpu():
    """``(cufinufft, cupy)``, or a StippleError saying what is missing."""
    try:
        import cufinufft
        import cupy
    except (ImportError, OSError) as error:  # OSError: a CUDA library the wheel links against is missing
        raise StippleError(f"backend cufinufft {NEEDS_GPU} ({error})") from None
    try:
        count = cupy.cuda.runtime.getDeviceCount()
    except cupy.cuda.runtime.CUDARuntimeError as error:
        raise StippleError(f"backend cufinufft found no usable CUDA device ({error})") from None
    if count < 1:
        raise StippleError("backend cufinufft found no CUDA device")
    return cufinufft, cupy


class CufinufftNufft:
    """2-D type-1/type-2 NUFFT on [0, 1)² through ``cufinufft`` (one plan of each type, points on the GPU).

    ``threads`` is kept for the interface (the mode-grid arithmetic around the transforms uses it); the GPU
    chooses its own parallelism. Single precision at ``epsilon >= SINGLE_PRECISION_EPSILON`` as on the CPU.
    """

    name = "cufinufft"

    def __init__(self, shape, epsilon, threads):
        cufinufft, self._cupy = require_gpu()
        self.shape = tuple(shape)
        self.epsilon = epsilon
        self.threads = threads
        self.counts = {"type1": 0, "type2": 0, "set_points": 0}
        self._real, self._complex = precision(epsilon)
        # cufinufft's tolerance is relative to the sum of |values|, like finufft's; a third keeps the same margin.
        options = dict(eps=max(epsilon / 3, 1e-14), dtype=np.dtype(self._complex).name)
        with self._failures("make its plans"):
            self._type1 = cufinufft.Plan(1, self.shape, isign=-1, **options)
            self._type2 = cufinufft.Plan(2, self.shape, isign=+1, **options)

    @contextlib.contextmanager
    def _failures(self, what):
        """cufinufft's failures (a RuntimeError with no cause, most often the GPU's memory) as one StippleError."""
        try:
            yield
        except RuntimeError as error:
            raise StippleError(
                f"backend cufinufft could not {what} on a {self.shape[0]} x {self.shape[1]} mode grid ({error}); "
                "the GPU may be out of memory: try fewer dots, a lower bandwidth or --backend ducc0"
            ) from None

    def set_points(self, points):
        scaled = 2 * np.pi * np.ascontiguousarray(points.T, dtype=self._real)
        with self._failures(f"set {len(points)} points"):
            # The plans keep references to these device arrays until the next call.
            x, y = self._cupy.asarray(scaled[0]), self._cupy.asarray(scaled[1])
            self._type1.setpts(x, y)
            self._type2.setpts(x, y)
        self.counts["set_points"] += 1

    def _execute(self, plan, batch):
        with self._failures("transform"):
            device = self._cupy.asarray(np.ascontiguousarray(batch, dtype=self._complex))
            out = self._cupy.stack([plan.execute(item) for item in device])
            return out.get().astype(np.complex128, copy=False)

    def type1(self, values):
        """``out[b, n] = sum_i values[b, i] exp(-2 pi i n . p_i)`` for a batch ``(B, M)``."""
        self.counts["type1"] += len(values)
        return self._execute(self._type1, values)

    def type2(self, coeffs):
        """``out[b, i] = sum_n coeffs[b, n] exp(+2 pi i n . p_i)`` for a batch ``(B, N1+1, N2+1)``."""
        self.counts["type2"] += len(coeffs)
        return self._execute(self._type2, coeffs)
