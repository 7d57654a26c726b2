"""Spreading the closest neighbours at the end of a run: a cheap step for the nearest-neighbour ratio's low tail.

The density-scaled run (``stipple.torus``) settles the energy and the picture in a few dozen iterations, but the
1st percentile of the nearest-neighbour ratio (``stipple.measures.evaluate.torus_clumps``: the distance to the nearest
dot over the hexagonal spacing of the density in the dot's own pixel) rises slowly. On the portrait those dots
are not close pairs: most sit in a light pixel next to a darker one, and their nearest neighbour, on the dark
side, is about one of its own spacings away (the neighbour's spacing is about 0.66 of theirs; only one in five
is its neighbour's nearest too). CG moves them out of the dark side's reach only as the fine arrangement along
the tone edges settles.

``spread_close`` moves every dot whose ratio is below a target (the ratios' ``SPREAD_PERCENTILE``-th percentile,
at least ``SPREAD_TARGET``) away from its nearest neighbour by half the shortfall, a few passes; a few CG
iterations then smooth the disturbance (``stipple.halftone.run``). ``spread_close_sphere`` is the same step on
the sphere (geodesic distances, moves along great circles), for maps (``stipple.sphere``).
"""

import numpy as np
from scipy.spatial import cKDTree

from .halftone import hexagonal_spacing
from .manifolds import Sphere
from .sampling import golden_angles, pixel_indices, pixel_positions

# A dot is spread when its nearest-neighbour distance is below this percentile of all dots' ratios to the
# hexagonal spacing of the density in their pixels, and at least this fraction of its spacing (the portrait after
# 100 iterations: p01 0.722; fixed targets 0.75/0.78/0.8 raised it to 0.738/0.753/0.761 after 3 CG iterations and
# the correction; on the dark rocket the p01 dots sit near 0.82 and a fixed 0.78 left them; docs/performance.md).
SPREAD_PERCENTILE = 5
SPREAD_TARGET = 0.78
# Passes of the step (each searches the nearest neighbours again): one pass leaves half of what three gain.
SPREAD_PASSES = 3


def hexagonal_spacing_at(points, weights):
    """Per dot (unit coordinates), the spacing in pixels of a hexagonal packing at the density of its pixel
    (``M w / sum(w)`` dots per pixel; infinite in pixels of zero density)."""
    density = len(points) * weights[pixel_indices(points, weights.shape)] / weights.sum()
    with np.errstate(divide="ignore", over="ignore"):
        return hexagonal_spacing(density, 1.0)


def spread_close(points, weights, target=None, passes=SPREAD_PASSES, threads=1):
    """Move every dot closer to its nearest neighbour than ``target`` times its hexagonal spacing
    (``hexagonal_spacing_at``) away from that neighbour by half the shortfall, ``passes`` times.

    The default ``target`` is the ``SPREAD_PERCENTILE``-th percentile of the ratios at the start (dots of
    positive density), at least ``SPREAD_TARGET``.

    Distances are periodic, in pixels (``points`` in unit coordinates, ``weights`` the density on the ``(H, W)``
    pixel grid, as in ``stipple.measures.evaluate.torus_neighbours``). Within a pass all dots move at once, each by at
    most ``target / 2`` of the smaller spacing of it and its neighbour; dots in pixels of zero density never move.
    Returns the new points (unit coordinates, in ``[0, 1)``) and the number of dots moved in the first pass.
    ``threads``: the nearest-neighbour queries' workers (the same result for any count).
    """
    rows, columns = weights.shape
    size = np.array([columns, rows], dtype=float)

    def nearest(pixels):
        distance, neighbour = cKDTree(pixels, boxsize=size).query(pixels, k=2, workers=threads)
        return distance[:, 1], neighbour[:, 1]

    def step_away(pixels, close, neighbour, distance, length):
        away = pixels[close] - pixels[neighbour]
        away -= size * np.rint(away / size)
        on_top = distance == 0
        away[on_top] = _directions(close[on_top])[:, :2]
        distance = np.where(on_top, 1.0, distance)
        moved = np.mod(pixels[close] + (length / np.maximum(distance, 1e-12))[:, None] * away, size)
        moved[moved >= size] = 0.0
        return moved

    pixels = pixel_positions(points, weights.shape)
    spacing = hexagonal_spacing_at(points, weights)
    pixels, moved = spread_apart(pixels, spacing, nearest, step_away, target, passes)
    return pixels / size, moved


def spread_close_sphere(points, local_density, target=None, passes=SPREAD_PASSES, threads=1):
    """``spread_close`` on the sphere: ``points`` are ``(M, 3)`` unit vectors, ``local_density`` the dots per
    steradian at each (``M w(p) / int w``; 0 where the density is), distances geodesic; a dot moves along the
    great circle away from its nearest neighbour. Returns the new unit vectors and the number moved in the first
    pass."""
    with np.errstate(divide="ignore"):
        spacing = hexagonal_spacing(np.asarray(local_density, dtype=float), 1.0)

    def nearest(vectors):
        chord, neighbour = cKDTree(vectors).query(vectors, k=2, workers=threads)
        # A dot without a neighbour (M = 1) keeps its infinite distance: clamped to pi, it was "close" to the
        # missing neighbour, and stipple sphere -M 1 ended in an IndexError (a hostile review).
        with np.errstate(invalid="ignore"):
            return np.where(
                np.isfinite(chord[:, 1]), 2 * np.arcsin(np.minimum(chord[:, 1] / 2, 1.0)), np.inf
            ), neighbour[:, 1]

    sphere = Sphere()

    def step_away(vectors, close, neighbour, distance, length):
        origin = vectors[close]
        away = origin - vectors[neighbour]
        on_top = distance == 0
        away[on_top] = _directions(close[on_top])
        away = sphere.project(origin, away)
        away /= np.maximum(np.linalg.norm(away, axis=1), 1e-300)[:, None]
        return sphere.retract(origin, length[:, None] * away)

    return spread_apart(np.array(points, dtype=float), spacing, nearest, step_away, target, passes)


def _directions(indices):
    """Unit vectors ``(cos a, sin a, 0)`` at golden-angle steps ``a`` of the dots' indices: the directions in which
    dots on top of another dot (distance 0, no direction away from it) move, a different one for each."""
    angles = golden_angles(indices)
    return np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)


def spread_apart(positions, spacing, nearest, step_away, target=None, passes=SPREAD_PASSES):
    """The passes of the spread step on any domain, in place on ``positions``.

    ``nearest(positions) -> (distance, neighbour)`` per dot; ``step_away(positions, close, neighbour, distance,
    length)`` the new positions of the dots ``close``, each moved by ``length`` away from its ``neighbour``.
    A dot of infinite ``spacing`` never moves. Returns ``positions`` and the number of dots moved in the first pass.
    """
    finite = np.isfinite(spacing)
    moved = 0
    for index in range(passes):
        distance, neighbour = nearest(positions)
        if target is None:
            ratios = distance[finite] / spacing[finite]
            ratios = ratios[np.isfinite(ratios)]  # a dot without a neighbour (M = 1) has none
            target = max(SPREAD_TARGET, float(np.percentile(ratios, SPREAD_PERCENTILE))) if ratios.size else 0.0
        close = np.flatnonzero(finite & (distance < target * np.where(finite, spacing, 0.0)))
        if index == 0:
            moved = close.size
        if close.size == 0:
            break
        # At most half the target times the pair's smaller spacing: a dot on a faint fringe beside a dense blob,
        # its own spacing tens of degrees, was thrown up to 82 degrees into an empty region (a held-out review).
        reach = 0.5 * target * np.minimum(spacing[close], spacing[neighbour[close]])
        length = np.minimum(0.5 * (target * spacing[close] - distance[close]), reach)
        positions[close] = step_away(positions, close, neighbour[close], distance[close], length)
    return positions, moved
