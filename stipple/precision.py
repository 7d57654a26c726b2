"""The floating-point types of the transforms (``stipple.nufft`` and ``stipple.transforms`` on the CPU,
``stipple.gpu`` on the GPU)."""

import numpy as np

# Transforms asked for this accuracy or a coarser one run in single precision (float32 points, complex64 values):
# the libraries reach it there, and their spreading and FFTs take about half the memory traffic.
SINGLE_PRECISION_EPSILON = 1e-5


def precision(epsilon):
    """``(real dtype, complex dtype)`` of the transforms for ``epsilon``."""
    if epsilon >= SINGLE_PRECISION_EPSILON:
        return np.float32, np.complex64
    return np.float64, np.complex128
