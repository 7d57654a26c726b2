"""Exact antialiased drawing of discs: a pixel is inked where its centre is inside a disc, for the union of one
ink's discs (``union_coverage_image``) and for inks multiplied on paper (``multiply_picture``)."""

import numpy as np

from ..errors import StippleError
from ..io.raster import draw_discs as _draw_discs
from .checks import check_colours, check_discs, check_size

SUPERSAMPLE = 4
MAX_GRID_PIXELS = 1 << 24


def union_coverage_image(centres, radii, size, shape, *, supersample=SUPERSAMPLE):
    """The covered fraction of each pixel by the union of discs: an antialiased drawing of black discs.

    Parameters
    ----------
    centres : numpy.ndarray
        ``(N, 2)`` disc centres ``(x, y)`` in canvas units (x right, y down).
    radii : numpy.ndarray
        ``(N,)`` radii in canvas units, ``>= 0``.
    size : (float, float)
        The canvas's ``(width, height)``.
    shape : (int, int)
        ``(rows, columns)`` of the image returned; pixel ``(i, j)`` is the canvas's rectangle
        ``[j, j + 1) * width / columns  x  [i, i + 1) * height / rows``.
    supersample : int
        Discs are drawn binary on a canvas ``supersample`` times finer (1 to 16) and area-averaged.

    Returns
    -------
    numpy.ndarray
        ``float32`` image of ``shape`` in [0, 1].

    Notes
    -----
    A fine pixel is inked when its centre lies inside a disc (strictly), so a disc's expected inked area over
    positions is exactly its area, and the union is exact at the fine pixels. (Pillow's ``ellipse`` is not
    suitable: it fills the pixels ``floor(x0) .. floor(x1)`` of the bounding box, both ends included, so the
    box ``(x - r, y - r, x + r, y + r)`` draws a disc ``(1 + 1 / (2 r))^2`` too large on average, +10 % at
    10 pixels, and with the box's far corner one pixel in, still a few % off for discs under 10 pixels.)
    """
    centres, radii = check_discs(centres, radii)
    width, height = check_size(size)
    rows, columns, s = check_picture(shape, supersample)
    fine = (rows * s, columns * s)
    scale = (fine[1] / width, fine[0] / height)
    mask = _draw_discs(fine, centres * scale, radii, scale)
    return _reduce(mask.view(np.uint8), rows, columns, s) / np.float32(s * s)


def multiply_picture(layers, colours, size, shape, *, paper=(1.0, 1.0, 1.0), supersample=SUPERSAMPLE):
    """An antialiased picture of layers of discs printed with multiplying inks on paper: ``(rows, columns, 3)``.

    Parameters
    ----------
    layers : list of (numpy.ndarray, numpy.ndarray)
        ``(centres, radii)`` per ink in canvas units (1 to 8 inks).
    colours : list of tuple
        Each ink's colour, RGB in [0, 1].
    size : (float, float)
        The canvas's ``(width, height)``.
    shape : (int, int)
        ``(rows, columns)`` of the picture.
    paper : tuple
        The paper's colour, RGB in [0, 1].
    supersample : int
        Fine pixels per pixel along each axis (1 to 16).

    Returns
    -------
    numpy.ndarray
        ``float32`` colours in [0, 1]: each fine pixel is ``paper * prod_k (1 - m_k (1 - p_k))`` with ``m_k``
        whether a disc of ink ``k`` covers its centre (as in ``union_coverage_image``), averaged over the fine
        pixels of a pixel. (Multiplying inks' pixel-averaged coverages instead would treat the inks as
        independent within each pixel, which dots of a joint stipple are not.)
    """
    if not 1 <= len(layers) <= 8:
        raise StippleError(f"layers must hold 1 to 8 inks, not {len(layers)}")
    absorb = check_colours(colours, len(layers))
    paper = 1.0 - check_colours([paper], 1)[0]  # the paper's reflectance
    width, height = check_size(size)
    rows, columns, s = check_picture(shape, supersample)
    if len(layers) == 1:  # one ink: linear in its coverage
        coverage = union_coverage_image(*layers[0], size, shape, supersample=s)
        return (paper * (1.0 - coverage[..., None] * absorb[0])).astype(np.float32)
    fine = (rows * s, columns * s)
    scale = (fine[1] / width, fine[0] / height)
    code = np.zeros(fine, dtype=np.uint8)
    for k, (centres, radii) in enumerate(layers):
        centres, radii = check_discs(centres, radii)
        mask = _draw_discs(fine, centres * scale, radii, scale)
        code |= mask.view(np.uint8) << np.uint8(k)
    inks = (np.arange(256)[:, None] >> np.arange(len(layers))) & 1  # (codes, inks)
    table = paper * np.prod(1.0 - inks[:, :, None] * absorb[None, :, :], axis=1)  # (codes, 3)
    table = np.round(table * 255).astype(np.uint8)
    picture = np.empty((rows, columns, 3), dtype=np.float32)
    for channel in range(3):
        values = table[:, channel][code]
        picture[..., channel] = _reduce(values, rows, columns, s) / np.float32(255 * s * s)
    return picture


def check_picture(shape, supersample):
    rows, columns = (int(v) for v in shape)
    if rows < 1 or columns < 1:
        raise StippleError(f"shape must be two positive integers (rows, columns), not {tuple(shape)!r}")
    if isinstance(supersample, bool) or not isinstance(supersample, int | np.integer) or not 1 <= supersample <= 16:
        raise StippleError(f"supersample must be an integer in [1, 16], not {supersample!r}")
    s = int(supersample)
    if rows * columns * s * s > 4 * MAX_GRID_PIXELS:
        raise StippleError(f"shape {rows}x{columns} with supersample {s} is too large to draw (at most 2^26 pixels)")
    return rows, columns, s


def _reduce(values, rows, columns, s):
    """Sums of ``s x s`` blocks of a ``uint8`` image (values up to 255), as ``float32``."""
    if s == 1:
        return values.astype(np.float32)
    # Strided additions: numpy's sum over a short axis took six times as long (a colour picture's 28 drawings
    # of its inks on the analysis grid spent 1.3 s here).
    blocks = values.reshape(rows, s, columns * s)
    strips = blocks[:, 0].astype(np.uint16 if s * 255 < 65536 else np.uint32)
    for k in range(1, s):
        strips += blocks[:, k]
    out = strips[:, 0::s].astype(np.float32)
    for k in range(1, s):
        out += strips[:, k::s]
    return out
