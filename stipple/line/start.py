"""The start of a one-line drawing: a tour through the dots of ``stipple torus``, resampled to equal steps.

M dots placed by the same method for the same image are evenly spread with the image's density; a short tour
through them is TSP art, whose strokes are already about evenly spaced. The tour: the first visits of the closed
walk around the dots' Euclidean minimum spanning tree (the walk that keeps the tree on one side: no crossing, no
step longer than the tree's longest edge), shortened by 2-opt (``stipple.tours``). Measured against the outline of
the spanning tree of random density samples (the start before, which had replaced a Moore-curve tour whose long
jumps across white became wires): on a compact silhouette the outline's out-and-back passes stay paired strokes
and the optimised line lost 2.6/3.7 dB to TSP art at M = 10000 (docs/line.md).
"""

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import minimum_spanning_tree
from scipy.spatial import Delaunay

from ..torus import halftone_torus
from ..tours import two_opt

MIN_CURVE_VERTICES = 4


def spanning_tree(points):
    """Edges ``(i, j)`` of the Euclidean minimum spanning tree of ``points`` (n, 2), ``n >= 3`` in general position."""
    simplices = Delaunay(points).simplices
    pairs = np.concatenate([simplices[:, [0, 1]], simplices[:, [1, 2]], simplices[:, [2, 0]]])
    pairs = np.unique(np.sort(pairs, axis=1), axis=0)
    # A zero length would read as a missing edge in the sparse matrix.
    lengths = np.maximum(np.linalg.norm(points[pairs[:, 0]] - points[pairs[:, 1]], axis=1), 1e-300)
    count = len(points)
    tree = minimum_spanning_tree(coo_matrix((lengths, (pairs[:, 0], pairs[:, 1])), shape=(count, count))).tocoo()
    return np.stack([tree.row, tree.col], axis=1)


def outline_walk(points, edges):
    """The closed walk around the plane tree ``edges``: the ``2 (n - 1)`` vertices it arrives at, in order.

    Arriving at a vertex along an edge, the walk leaves along the next edge counterclockwise from the one it came
    by (a leaf sends it back): the rule that traces a face of a plane graph, here the tree's one face. Directed
    edge ``e`` is ``edges[e]`` for ``e < n - 1`` and reversed for ``e >= n - 1``.
    """
    source = np.concatenate([edges[:, 0], edges[:, 1]])
    target = np.concatenate([edges[:, 1], edges[:, 0]])
    direction = points[target] - points[source]
    angle = np.arctan2(direction[:, 1], direction[:, 0])
    count = len(source)
    rotation = np.lexsort((angle, source))  # directed edges grouped by source, counterclockwise
    rank = np.empty(count, dtype=np.int64)
    rank[rotation] = np.arange(count)
    first = np.searchsorted(source[rotation], target)
    degree = np.bincount(source, minlength=len(points))[target]
    reverse = (np.arange(count) + count // 2) % count
    following = rotation[first + (rank[reverse] - first + 1) % degree]
    walk = np.empty(count, dtype=np.int64)
    edge = 0
    for step in range(count):
        walk[step] = edge
        edge = following[edge]
    return target[walk]


def tree_tour(points):
    """A closed tour through ``points`` (vertex order): the first visits of the walk around their spanning tree."""
    visits = outline_walk(points, spanning_tree(points))
    _, first = np.unique(visits, return_index=True)
    return visits[np.sort(first)]


def resample_closed(points, count):
    """``count`` points equally spaced by arclength along the closed polygon through ``points``."""
    closed = np.vstack([points, points[:1]])
    cumulative = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    targets = np.arange(count) * cumulative[-1] / count
    return np.stack([np.interp(targets, cumulative, closed[:, axis]) for axis in range(2)], axis=1)


def initial_loop(weights, n_vertices, seed=0, threads=None):
    """A closed loop of ``n_vertices`` equally spaced vertices (unit coordinates): TSP art, resampled.

    ``n_vertices`` dots of ``stipple.torus.halftone_torus`` (``seed``, ``threads``), toured by ``tree_tour`` and
    2-opt. The loop has the tour's length; ``draw_line`` then stretches it to the line's length.
    """
    rows, columns = weights.shape
    # The line's tuned start: the single-image run as it was before the coarse-to-fine start (docs/performance.md).
    dots = halftone_torus(
        weights, n_vertices, seed=seed, threads=threads, precondition=False, bandwidth_factor=1.0, levels=False
    )
    pixels = np.mod(dots.points, 1.0) * np.array([columns, rows])
    order = two_opt(pixels, tree_tour(pixels)) if n_vertices > MIN_CURVE_VERTICES else np.arange(n_vertices)
    return resample_closed(pixels[order], n_vertices) / np.array([columns, rows])
