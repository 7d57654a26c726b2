"""Pen plotters: a short pen-up path through the dots (greedy nearest neighbour, then 2-opt), and the pen paths
that draw a dot."""

import numpy as np
from scipy.spatial import cKDTree

from ..tours import two_opt
from .styles import DOT_STYLES

NEIGHBOURS = 8


def path_length(centres):
    """Total travel between consecutive dots, in the units of ``centres``."""
    return float(np.sum(np.linalg.norm(np.diff(centres, axis=0), axis=1)))


def closed_length(points):
    """Length of the closed polygon through ``points`` (a one-line drawing's path)."""
    return float(np.sum(np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)))


def greedy_order(centres):
    """Visit order starting at the dot nearest the origin, always moving to the nearest unvisited dot."""
    count = len(centres)
    tree = cKDTree(centres)
    visited = np.zeros(count, dtype=bool)
    order = np.empty(count, dtype=int)
    current = int(np.argmin(np.sum(centres**2, axis=1)))
    for step in range(count):
        order[step] = current
        visited[current] = True
        if step == count - 1:
            break
        k = NEIGHBOURS
        while True:
            _, candidates = tree.query(centres[current], k=min(k, count))
            free = [c for c in np.atleast_1d(candidates) if not visited[c]]
            if free:
                current = int(free[0])
                break
            if k >= count:
                current = int(np.flatnonzero(~visited)[0])
                break
            k *= 4
    return order


def plotter_order(centres):
    """A short visiting order (greedy nearest neighbour improved by 2-opt, ``stipple.tours``) and the path lengths
    before/after."""
    order = two_opt(centres, greedy_order(centres), closed=False)
    return order, path_length(centres), path_length(centres[order])


def pen_order(points, centres):
    """``points`` reordered along a short pen path through ``centres`` (their places on the drawing), and the
    pen-up travel before and after, in the units of ``centres``."""
    order, before, after = plotter_order(centres)
    return points[order], before, after


def physical_centres(points, shape, width):
    """Torus points (unit coordinates of an image of ``shape = (H, W)``) on the SVG's physical canvas, in the
    unit of ``width = (value, unit)``."""
    rows, columns = shape
    return points * np.array([columns, rows]) * (width[0] / columns)


SEGMENTS_PER_TURN = 24


def circle_path(centre, radius, segments=SEGMENTS_PER_TURN):
    """A closed polygon of ``segments`` sides around ``centre`` (complex ``x + iy``), as complex vertices."""
    angles = np.linspace(0, 2 * np.pi, segments + 1)
    return centre + radius * np.exp(1j * angles)


def spiral_path(centre, radius, pen_width, segments=SEGMENTS_PER_TURN):
    """One pen-down path that fills a disc: an Archimedean spiral of pitch ``pen_width`` out to the
    outermost stroke's radius ``radius - pen_width / 2``, then a full circle there (the disc's edge)."""
    outer = max(radius - pen_width / 2, 0.0)
    turns = outer / pen_width
    if turns <= 0.5:
        return circle_path(centre, outer, segments) if outer > 0 else np.array([centre, centre + pen_width / 10])
    end = 2 * np.pi * turns
    angles = np.linspace(0, end, max(int(np.ceil(segments * turns)), 2) + 1)
    spiral = centre + outer * (angles / end) * np.exp(1j * angles)
    edge = centre + outer * np.exp(1j * (end + np.linspace(0, 2 * np.pi, segments + 1)[1:]))
    return np.concatenate([spiral, edge])


def dot_paths(centres, radius, style="circle", pen_width=0.3):
    """Pen paths (complex vertex arrays, vpype's line format) that draw a dot of ``radius`` at each centre.

    Parameters
    ----------
    centres : numpy.ndarray
        ``(M, 2)`` dot centres in drawing units.
    radius : float or numpy.ndarray
        Dot radius in the same units, one for all dots or one per dot.
    style : {"circle", "filled", "point"}
        "circle": the dot's outline (the pen's centre on ``radius - pen_width / 2``); "filled": a spiral that
        inks the whole disc with strokes ``pen_width`` apart; "point": a stroke a tenth of the pen wide, which
        the pen draws as a dot of its own width (plotters skip zero-length paths).
    pen_width : float
        Width of the pen's stroke, same units.

    Returns
    -------
    list of numpy.ndarray
    """
    if style not in DOT_STYLES:
        raise ValueError(f"dot style must be one of {', '.join(DOT_STYLES)}, not {style!r}")
    positions = np.asarray(centres, dtype=np.float64).reshape(-1, 2) @ np.array([1.0, 1j])
    radii = np.broadcast_to(np.asarray(radius, dtype=np.float64), positions.shape)
    if style == "point":
        return [np.array([z, z + pen_width / 10]) for z in positions]
    if style == "circle":
        return [circle_path(z, max(r - pen_width / 2, pen_width / 20)) for z, r in zip(positions, radii, strict=True)]
    return [spiral_path(z, r, pen_width) for z, r in zip(positions, radii, strict=True)]
