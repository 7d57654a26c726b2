"""The start of a one-line drawing: a closed loop through density samples, in Moore-curve order.

The Hilbert curve is open: it starts and ends at two corners of one side, so a tour in Hilbert order closes with a
jump the length of that side, and 2-opt with nearest-neighbour candidates cannot remove it (no edge near one end
leads near the other). Resampled to equal steps, that jump became a straight run of vertices along the image's top
edge which CG never pulled apart: the "wire" of the portrait at M = 20000 (issue #25). The Moore curve is the
closed Hilbert curve: four Hilbert curves, one per quadrant, whose ends meet, so the last cell is next to the first.
"""

import numpy as np

from .sampling import hilbert_index, sample_image
from .tours import two_opt

MIN_CURVE_VERTICES = 4
INITIAL_TOURS = 6
CURVE_ORDER = 16


def moore_index(x, y, order=CURVE_ORDER):
    """Index along the closed Moore curve of the ``2^order`` grid of integer cells ``(x, y)`` (``order >= 1``).

    The quadrants are visited in the order ``x < s, y < s``; ``x < s, y >= s``; ``x >= s, y >= s``;
    ``x >= s, y < s`` (``s = 2^(order - 1)``), each by a Hilbert curve turned so that it enters next to where the
    previous one left; the curve starts at ``(s - 1, 0)`` and ends next to it at ``(s, 0)``.
    """
    half = 1 << (order - 1)
    x, y = np.asarray(x, dtype=np.int64), np.asarray(y, dtype=np.int64)
    right, upper = x >= half, y >= half
    local_x, local_y = x - half * right, y - half * upper
    # Left quadrants: a Hilbert curve turned a quarter clockwise (u = y, v = s - 1 - x); right ones anticlockwise.
    u = np.where(right, half - 1 - local_y, local_y)
    v = np.where(right, local_x, half - 1 - local_x)
    quadrant = np.where(right, np.where(upper, 2, 3), np.where(upper, 1, 0))
    if order == 1:
        return quadrant
    return quadrant * half * half + hilbert_index(u, v, order - 1)


def moore_tour(weights, count, rng):
    """``count`` density samples (pixel units) in Moore-curve order: a closed loop through the image.

    The curve's square is stretched onto the image's rectangle, so that the loop covers all of a wide or tall
    image and its closing step stays short.
    """
    rows, columns = weights.shape
    unit = sample_image(weights, rng, count)
    cells = np.minimum((unit * (1 << CURVE_ORDER)).astype(np.int64), (1 << CURVE_ORDER) - 1)
    order = np.argsort(moore_index(cells[:, 0], cells[:, 1]), kind="stable")
    return unit[order] * np.array([columns, rows])


def closed_length(points):
    """Length of the closed polygon through ``points``."""
    return float(np.sum(np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)))


def resample_closed(points, count):
    """``count`` points equally spaced by arclength along the closed polygon through ``points``."""
    closed = np.vstack([points, points[:1]])
    cumulative = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    targets = np.arange(count) * cumulative[-1] / count
    return np.stack([np.interp(targets, cumulative, closed[:, axis]) for axis in range(2)], axis=1)


def initial_loop(weights, n_vertices, length, rng):
    """A closed loop of ``n_vertices`` equally spaced vertices (unit coordinates) of length about ``length`` px.

    A Moore-curve tour through density samples, shortened by 2-opt (which removes its crossings), with as many
    samples as make the tour about ``length`` long (a tour's length grows like the square root of its samples),
    resampled by arclength.
    """
    rows, columns = weights.shape
    count = max(MIN_CURVE_VERTICES, n_vertices // 4)
    best = None
    for _ in range(INITIAL_TOURS):
        tour = moore_tour(weights, count, rng)
        loop = resample_closed(tour[two_opt(tour)], n_vertices)
        ratio = length / closed_length(loop)
        if best is None or abs(np.log(ratio)) < abs(np.log(best[1])):
            best = (loop, ratio)
        count = int(np.clip(count * ratio**2, MIN_CURVE_VERTICES, 8 * n_vertices))
    return best[0] / np.array([columns, rows])
