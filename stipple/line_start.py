"""The start of a one-line drawing: the outline of a minimum spanning tree through density samples.

A closed walk around a plane tree, keeping the tree on one side, passes along every edge twice (out and back) and
never crosses itself; each step is an edge of the tree, so the loop has no jump longer than the tree's longest
edge. The Euclidean minimum spanning tree (a subgraph of the Delaunay triangulation) joins samples by their
nearest links: inside a dark region its edges are about one sample spacing long, and only the few edges that join
separate dark regions cross white. This replaced a tour in Moore-curve order shortened by 2-opt (issue #25): that
tour kept about a dozen edges over five times the mean, which crossed white between the thin parts of a
silhouette; resampled to equal steps they became wires that the optimiser pulled taut, dragging the line out of
the shape (a horse's legs emptied, a wire ran along the ground between its hooves).
"""

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import minimum_spanning_tree
from scipy.spatial import Delaunay

from .sampling import sample_image

MIN_CURVE_VERTICES = 4
INITIAL_TOURS = 6
# The loop runs this many mean stroke spacings (W H / L) off the tree, into the wedge between consecutive edges.
# Measured at M = 3000 (portrait and a shapes image, PSNR at sigma 2/4 px): 0.1 gave 17.4/28.5 and 25.3/31.9 dB,
# 0.25 17.5/28.3 and 25.9/32.6, 0.5 17.5/28.9 and 26.0/32.9, 1.0 16.7/27.9 and 24.9/31.7.
OFFSET_SPACINGS = 0.5
# Samples per vertex of the first try (the tree's outline is about twice the tree, which is about 0.65 sqrt(n A)).
FIRST_SAMPLES_PER_VERTEX = 0.1


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
    """The closed walk around the plane tree ``edges``: directed edges in walk order, and each one's angle.

    Directed edge ``e`` is ``edges[e]`` for ``e < n - 1`` and reversed for ``e >= n - 1``. Arriving at a vertex
    along an edge, the walk leaves along the next edge counterclockwise from the one it came by (a leaf sends it
    back): the rule that traces a face of a plane graph, here the tree's one face.
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
    return walk, following, target, angle


def tree_outline(points, edges, offset):
    """The outline of the plane tree ``edges`` on ``points``: one point per visit of a vertex.

    A visit between the edge in and the edge out, which bound a wedge of angle ``sweep`` (the whole turn at a
    leaf), is placed ``offset`` off the vertex along the wedge's bisector. The ``2 (n - 1)`` points form a closed
    polygon without crossings for small ``offset``.
    """
    walk, following, target, angle = outline_walk(points, edges)
    count = len(target)
    reverse = (walk + count // 2) % count
    start = angle[reverse]
    sweep = np.mod(angle[following[walk]] - start, 2 * np.pi)
    sweep[sweep < 1e-12] = 2 * np.pi
    bisector = start + sweep / 2
    return points[target[walk]] + offset * np.stack([np.cos(bisector), np.sin(bisector)], axis=1)


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

    The outline of the minimum spanning tree of density samples, offset ``OFFSET_SPACINGS`` mean stroke
    spacings, with as many samples as make it about ``length`` long (an outline's length grows like the square
    root of its samples; the best of ``INITIAL_TOURS`` tries), resampled by arclength.
    """
    rows, columns = weights.shape
    offset = OFFSET_SPACINGS * rows * columns / length
    count = max(MIN_CURVE_VERTICES, int(FIRST_SAMPLES_PER_VERTEX * n_vertices))
    best = None
    for _ in range(INITIAL_TOURS):
        samples = sample_image(weights, rng, count) * np.array([columns, rows])
        loop = resample_closed(tree_outline(samples, spanning_tree(samples), offset), n_vertices)
        ratio = length / closed_length(loop)
        if best is None or abs(np.log(ratio)) < abs(np.log(best[1])):
            best = (loop, ratio)
        count = int(np.clip(count * ratio**2, MIN_CURVE_VERTICES, 8 * n_vertices))
    return best[0] / np.array([columns, rows])
