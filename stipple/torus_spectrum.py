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


def image_coefficients(weights, bandwidths, dft=None):
    """Exact ``w_n = int_{[0,1)^2} w(u) e^{-2 pi i n.u} du`` of the pixel-constant image, ``|n_j| <= N_j/2``.

    Returns an array of shape ``(N1+1, N2+1)``, first axis ``n1`` (x, columns), second ``n2`` (y, rows). The
    cell factors are separable: computed per axis (at M = 10^6 the 2-D grid has 14 million modes). ``dft`` is
    ``image_dft`` at these or larger bandwidths, where it is known (``PixelDensity``).
    """
    rows, columns = weights.shape
    dft = image_dft(weights, bandwidths) if dft is None else centred_block(dft, bandwidths)
    n1, n2 = (centred_modes(bandwidth) for bandwidth in bandwidths)
    factors = np.outer(cell_factor(n1, columns), cell_factor(n2, rows)) / (rows * columns)
    return np.ascontiguousarray(dft * factors)


# An image with this many pixels or more per mode along both axes has its DFT taken at the modes' columns only.
PARTIAL_DFT_PIXELS = 4


def image_dft(weights, bandwidths):
    """The DFT of ``weights`` at the modes ``|n_j| <= N_j/2``, shape ``(N1+1, N2+1)`` (``n1``, columns, first): the
    whole FFT's, or, on an image of ``PARTIAL_DFT_PIXELS`` pixels per mode or more, the same sums from a real FFT
    of every row and an FFT of the modes' columns only (a 12-megapixel photo with 30000 dots: 0.3 s for 1.6)."""
    rows, columns = weights.shape
    n1, n2 = (centred_modes(bandwidth) for bandwidth in bandwidths)
    if columns < PARTIAL_DFT_PIXELS * len(n1) or rows < PARTIAL_DFT_PIXELS * len(n2):
        return np.fft.fft2(weights)[np.ix_(n2 % rows, n1 % columns)].T
    half = np.fft.rfft(weights, axis=1)[:, : n1[-1] + 1]
    # A real row's frequency -n is the conjugate of n.
    row_sums = np.concatenate([np.conj(half[:, :0:-1]), half], axis=1)
    return np.fft.fft(row_sums, axis=0)[n2 % rows].T


def centred_block(modes, bandwidths):
    """The modes ``|n_j| <= N_j/2`` of a centred mode array of larger (or equal) bandwidths."""
    offsets = [(size - (bandwidth + 1)) // 2 for size, bandwidth in zip(modes.shape, bandwidths, strict=True)]
    return modes[offsets[0] : offsets[0] + bandwidths[0] + 1, offsets[1] : offsets[1] + bandwidths[1] + 1]


class PixelDensity:
    """A density given by pixels (checked and scaled, ``stipple.torus.torus_problem``) and what the problems built
    on it share, each computed once: its DFT at the largest bandwidths asked for, read at every smaller one
    (``coefficients``), and its ``peak_ratio`` (``stipple.torus.default_bandwidth``). A run builds its coarse
    levels and its correction's coarse problems on the same image, at smaller bandwidths than its own: a
    12-megapixel photo took 0.5 s a transform and 0.25 s a peak, four times each."""

    def __init__(self, weights):
        self.weights = weights
        self._dft = None

    @property
    def shape(self):
        return self.weights.shape

    @cached_property
    def peak_ratio(self):
        return peak_ratio(self.weights)

    def coefficients(self, bandwidths):
        """``image_coefficients`` of the pixels at ``bandwidths``."""
        known = (0, 0) if self._dft is None else tuple(size - 1 for size in self._dft.shape)
        if bandwidths[0] > known[0] or bandwidths[1] > known[1]:
            self._dft = image_dft(self.weights, tuple(map(max, bandwidths, known)))
        return image_coefficients(self.weights, bandwidths, self._dft)


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
