"""The torus's Fourier side: its side lengths and per-axis bandwidths, an image's exact coefficients, and the ball
kernel on the mode grid with its near-field split (cached for small grids)."""

from functools import cached_property, lru_cache

import numpy as np

from .halftone import even_at_least_2
from .kernels import NearKernel, ball_kernel, ball_profile
from .peaks import peak_ratio
from .transforms import centred_modes

# Near-field radius times the bandwidth: eps = 3 / N (the smooth part's force error is ~0.7 % of the kernel's
# contact force; 0.3 % at 4 / N for 1.8 times the pairs).
NEAR_FIELD_REACH = 3.0


def torus_near_kernel(bandwidth, scale):
    """The ball kernel's short range for ``bandwidth``: radius ``3/N``, at most a quarter of the shorter side."""
    return NearKernel(ball_profile, min(NEAR_FIELD_REACH / bandwidth, 0.25 * min(scale)))


def torus_scale(shape):
    """Physical side lengths ``(W/L, H/L)``, ``L = max(W, H)``, of the torus for a ``(H, W)`` grid."""
    rows, columns = shape
    longest = max(rows, columns)
    return np.array([columns / longest, rows / longest])


def axis_bandwidths(bandwidth, shape):
    """Per-axis bandwidths ``(N1, N2)`` (x, y) of a ``(H, W)`` grid, even, giving the same resolution in both
    directions."""
    return scaled_bandwidths(bandwidth, torus_scale(shape))


def scaled_bandwidths(bandwidth, scale):
    """Per-axis bandwidths ``(N1, N2)`` for a torus of side lengths ``scale``: ``bandwidth`` along the longer side,
    in proportion along the other, each even."""
    return tuple(even_at_least_2(bandwidth * side) for side in scale)


def cell_factor(k, cells):
    """``(1 - e^{-2 pi i k / n}) / (2 pi i k / n)``: the Fourier integral of one cell of ``n``, ``1`` at ``k = 0``."""
    z = 2j * np.pi * np.asarray(k, dtype=float) / cells
    safe = np.where(z == 0, 1.0, z)
    return np.where(z == 0, 1.0, (1 - np.exp(-safe)) / safe)


def image_coefficients(weights, bandwidths, spectrum=None):
    """Exact ``w_n = int_{[0,1)^2} w(u) e^{-2 pi i n.u} du`` of the pixel-constant image, ``|n_j| <= N_j/2``.

    Returns an array of shape ``(N1+1, N2+1)``, first axis ``n1`` (x, columns), second ``n2`` (y, rows). The
    cell factors are separable: computed per axis (at M = 10^6 the 2-D grid has 14 million modes). ``spectrum``
    is ``weights``' FFT where it is known (``PixelDensity``).
    """
    rows, columns = weights.shape
    spectrum = np.fft.fft2(weights) if spectrum is None else spectrum
    n1, n2 = (centred_modes(bandwidth) for bandwidth in bandwidths)
    dft = spectrum[np.ix_(n2 % rows, n1 % columns)].T
    factors = np.outer(cell_factor(n1, columns), cell_factor(n2, rows)) / (rows * columns)
    return np.ascontiguousarray(dft * factors)


class PixelDensity:
    """A density given by pixels (checked and scaled, ``stipple.torus.torus_problem``) and what the problems built
    on it share, each computed once: its FFT, read at every bandwidth (``coefficients``), and its ``peak_ratio``
    (``stipple.torus.default_bandwidth``). A run builds its coarse levels and its correction's coarse problems on
    the same image: a 12-megapixel photo took 0.5 s a transform and 0.25 s a peak, four times each."""

    def __init__(self, weights):
        self.weights = weights

    @property
    def shape(self):
        return self.weights.shape

    @cached_property
    def spectrum(self):
        return np.fft.fft2(self.weights)

    @cached_property
    def peak_ratio(self):
        return peak_ratio(self.weights)

    def coefficients(self, bandwidths):
        """``image_coefficients`` of the pixels at ``bandwidths``."""
        return image_coefficients(self.weights, bandwidths, self.spectrum)


def radial_on_modes(radial, bandwidths, scale):
    """``radial(|xi|)``, ``xi = (n1 / scale_x, n2 / scale_y)``, on the mode grid: the physical frequencies.

    Evaluated on the quadrant ``n1, n2 >= 0`` only (a quarter of the modes) and mirrored: ``|xi|`` is even in both.
    """
    n1, n2 = (np.arange(bandwidth // 2 + 1) for bandwidth in bandwidths)
    quadrant = radial(np.hypot.outer(n1 / scale[0], n2 / scale[1]))
    mirror = [np.abs(centred_modes(bandwidth)) for bandwidth in bandwidths]
    return quadrant[np.ix_(*mirror)]


def torus_kernel(bandwidths, scale):
    """``kB(|xi|)`` on the mode grid; ``k_0 = 0``."""
    kernel = radial_on_modes(ball_kernel, bandwidths, scale)
    kernel[bandwidths[0] // 2, bandwidths[1] // 2] = 0.0
    return kernel


# A video's frames (and a run's coarse problems) build the same kernels: up to 16 on grids of CACHED_MODES modes or
# fewer are kept, 128 MiB at most (a colour frame builds 10-13; their quadrature took 4.5 ms of a 90 ms warm frame).
CACHED_MODES = 2**19


def torus_kernels(bandwidth, shape, near_field):
    """``(smooth, cross, near)``: ``torus_kernel`` at ``bandwidth`` for a ``shape`` image less the near field's share
    ``cross`` (``near``'s plane coefficients), or ``(kernel, None, None)``; read-only, cached on small grids."""
    modes = np.prod(np.add(axis_bandwidths(bandwidth, shape), 1))
    return (_cached_kernels if modes <= CACHED_MODES else _kernels)(bandwidth, tuple(shape), bool(near_field))


def _kernels(bandwidth, shape, near_field):
    scale, bandwidths = torus_scale(shape), axis_bandwidths(bandwidth, shape)
    kernel = torus_kernel(bandwidths, scale)
    if not near_field:
        return _read_only(kernel), None, None
    near = torus_near_kernel(bandwidth, scale)
    cross = radial_on_modes(near.plane_coefficients, bandwidths, scale)
    return _read_only(kernel - cross), _read_only(cross), near


def _read_only(array):
    array.flags.writeable = False
    return array


_cached_kernels = lru_cache(maxsize=16)(_kernels)
