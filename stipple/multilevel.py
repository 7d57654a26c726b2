"""Coarse-to-fine starts: solve a quarter of the dots at half the bandwidth, split each into its share, repeat.

Most of a cold run's iterations move dots over long distances, and those distances are long in units of the dot
spacing. A problem with a quarter of the dots (``default_bandwidth`` then halves ``N``) settles the same
long-range transport at a quarter of the cost per iteration; its solution, split in place, is a start whose
tone is right down to the coarse spacing. Applied recursively, the full problem only has to settle its own
local arrangement.

``split_points`` is the transfer from one level to the next:

- **shares**: the density's mass in each coarse dot's cell (the periodic Voronoi cell, measured on the pixels,
  sub-sampled so that every cell gets several samples), accumulated over the coarse dots in Hilbert-curve order
  and rounded: dot ``c`` gets ``round(M C_c) - round(M C_{c-1})`` children, with ``C`` the cumulative mass
  fraction. Every cell then holds its mass in children to within one, and any run of consecutive cells along the
  curve too.
- **positions**: the children of a dot are the points nearest to it of the half-spacing lattice spanned by its
  two nearest coarse neighbours (a square or hexagonal coarse lattice becomes the lattice of half its spacing,
  exactly, with four children per dot), so the fine start inherits the coarse arrangement's regularity instead
  of the clumps of random positions.
"""

import time

import numpy as np
from scipy.spatial import cKDTree

from .manifolds import Sphere
from .optimize import minimize, time_left
from .sampling import block_sums, hilbert_index
from .transforms import spherical_angles

# Dots per level: each coarser level has 1/RATIO of the dots of the next (4: half the spacing, half the N).
RATIO = 4
# The coarsest level has at least this many dots; a problem with fewer than RATIO times as many has no levels.
SMALLEST = 2000
# CG iterations per coarse level at most (each level also stops by its problem's ``settle``).
LEVEL_ITERATIONS = 50
# Samples of the density per coarse cell (at least) when measuring the cells' masses.
SAMPLES_PER_CELL = 16
# Images of more than this many times SAMPLES_PER_CELL pixels per coarse dot are measured in blocks of pixels (a
# 12-megapixel photo's 7500 coarse dots: the pixels one by one took 7 s).
BLOCK_SAMPLES = 4
# Candidate lattice points per dot: offsets (i + 1/2, j + 1/2) half-vectors, |i|, |j| < LATTICE_REACH (36), more
# for a dot with more children (a narrow peak that the coarse level's bandwidth does not resolve gives a coarse dot
# 40-50 children: reusing a candidate put children on top of each other, which no later step separates).
LATTICE_REACH = 3
# The second neighbour vector must be at least this far from parallel to the first (|sine| of the angle); else
# (dots along a line) it is the first turned by a right angle, so that the lattice's points stay distinct.
MIN_LATTICE_SINE = 0.5


def level_counts(n_points, ratio=RATIO, smallest=None):
    """Dot counts of the coarse levels, coarsest first (empty when ``n_points < ratio * smallest``; default
    ``SMALLEST``)."""
    smallest = SMALLEST if smallest is None else smallest
    counts = []
    count = n_points
    while count // ratio >= smallest:
        count = int(round(count / ratio))
        counts.append(count)
    return counts[::-1]


def _periodic_tree(positions, scale):
    return cKDTree(positions, boxsize=np.asarray(scale, dtype=float) * (1 + 1e-12))


def cell_masses(weights, points, scale, samples_per_cell=SAMPLES_PER_CELL, threads=1):
    """The density's mass in the periodic Voronoi cell of each of ``points`` (unit coordinates), as fractions.

    The mass is sampled on a grid of cells, each of whose mass goes to the dot nearest to its centre (physical
    distances): every pixel cut into ``f x f`` sub-pixels (``f`` the least giving ``samples_per_cell`` sub-pixels
    per dot), or, on an image of more than ``BLOCK_SAMPLES`` times that many pixels, the pixels gathered into
    ``b x b`` blocks (``b`` the largest leaving ``BLOCK_SAMPLES * samples_per_cell`` blocks per dot).
    """
    scale = np.asarray(scale, dtype=float)
    tree = _periodic_tree(np.mod(points, 1.0) * scale, scale)
    block, factor = sampling_grid(weights.size, len(points), samples_per_cell)
    bands = _pixel_blocks(weights, block, scale) if block > 1 else _sub_pixels(weights, factor, scale)
    masses = np.zeros(len(points))
    for positions, values in bands:
        inked = values > 0
        _, owner = tree.query(positions[inked], workers=threads)
        masses += np.bincount(owner, weights=values[inked], minlength=len(points))
    return masses / masses.sum()


def sampling_grid(cells, dots, samples_per_cell):
    """``(block, factor)``: a grid of ``cells`` cells measured for ``dots`` dots' masses is gathered into blocks of
    ``block x block`` cells where ``block > 1`` (``BLOCK_SAMPLES * samples_per_cell`` blocks per dot or more), else
    cut into ``factor x factor`` sub-cells (``samples_per_cell`` or more per dot)."""
    block = int(np.sqrt(cells / (BLOCK_SAMPLES * samples_per_cell * dots)))
    return block, max(1, int(np.ceil(np.sqrt(samples_per_cell * dots / cells))))


# Samples a band of ``cell_masses`` holds at most: bounded memory at any size.
BAND_SAMPLES = 2**20


def _sub_pixels(weights, factor, scale):
    """``(centres, masses)`` of the ``factor x factor`` sub-pixels of every pixel, a band of rows at a time."""
    rows, columns = weights.shape
    fine_x = (np.arange(columns * factor) + 0.5) / (columns * factor) * scale[0]
    band = max(1, BAND_SAMPLES // (columns * factor * factor))
    for top in range(0, rows, band):
        block = weights[top : top + band]
        fine_rows = np.arange(top * factor, (top + len(block)) * factor)
        fine_y = (fine_rows + 0.5) / (rows * factor) * scale[1]
        xx, yy = np.meshgrid(fine_x, fine_y)
        values = np.repeat(np.repeat(block, factor, axis=0), factor, axis=1).ravel()
        yield np.stack([xx.ravel(), yy.ravel()], axis=1), values


def _pixel_blocks(weights, block, scale):
    """``(centres, masses)`` of the ``block x block`` blocks of pixels (smaller along the far edges), a band of
    block rows at a time."""
    rows, columns = weights.shape
    band = block * max(1, BAND_SAMPLES // -(-columns // block))
    for top in range(0, rows, band):
        masses, (centre_y, centre_x) = block_sums(weights[top : top + band], block)
        xx, yy = np.meshgrid(centre_x / columns * scale[0], (centre_y + top) / rows * scale[1])
        yield np.stack([xx.ravel(), yy.ravel()], axis=1), masses.ravel()


def shares(masses, points, n_points):
    """Children per dot: ``round(M C_c) - round(M C_{c-1})`` with ``C`` the cumulative mass fraction of the dots
    taken in Hilbert-curve order of their positions; they sum to ``n_points`` and each is within one of
    ``M * masses[c]``."""
    cells = np.minimum((np.mod(points, 1.0) * 2**16).astype(np.int64), 2**16 - 1)
    order = np.argsort(hilbert_index(cells[:, 0], cells[:, 1], 16), kind="stable")
    cumulative = np.cumsum(masses[order])
    cumulative /= cumulative[-1]
    bounds = np.rint(np.concatenate([[0.0], cumulative]) * n_points).astype(np.int64)
    counts = np.empty(len(points), dtype=np.int64)
    counts[order] = np.diff(bounds)
    return counts


def lattice_vectors(points, scale, threads=1):
    """Per dot, two neighbour vectors (physical): the nearest neighbour and the one of the next five nearest whose
    direction is closest to a right angle to it."""
    scale = np.asarray(scale, dtype=float)
    positions = np.mod(points, 1.0) * scale
    tree = _periodic_tree(positions, scale)
    neighbours = min(7, len(points))
    _, index = tree.query(positions, k=neighbours, workers=threads)
    delta = positions[index[:, 1:]] - positions[:, None, :]
    delta -= scale * np.rint(delta / scale)
    return neighbour_pair(delta)


def neighbour_pair(delta, normals=None):
    """From the vectors to each dot's nearest neighbours, nearest first (``(dots, k, dim)``): the first, and the
    one of the others whose direction is closest to a right angle to it; where even that one is within
    ``MIN_LATTICE_SINE`` of parallel, the first turned by a right angle (in the plane, or about the dots'
    ``normals`` on a surface)."""
    first = delta[:, 0]
    length = np.linalg.norm(delta, axis=2)
    cosine = np.abs(np.einsum("ij,ikj->ik", first, delta[:, 1:])) / np.maximum(length[:, :1] * length[:, 1:], 1e-300)
    best = np.argmin(cosine, axis=1)
    second = delta[np.arange(len(delta)), 1 + best]
    parallel = cosine[np.arange(len(delta)), best] ** 2 > 1 - MIN_LATTICE_SINE**2
    if parallel.any():
        second = second.copy()
        turned = first[parallel]
        if normals is None:
            second[parallel] = np.stack([-turned[:, 1], turned[:, 0]], axis=1)
        else:
            second[parallel] = np.cross(normals[parallel], turned)
    return first, second


def lattice_children(points, counts, scale, threads=1):
    """Each dot's ``counts`` children: the points nearest to it of the lattice spanned by half its two neighbour
    vectors, shifted by a quarter of both (so that four children sit symmetrically around it). Unit coordinates,
    the children of dot ``c`` consecutive, in dot order."""
    scale = np.asarray(scale, dtype=float)
    owner, chosen = lattice_offsets(*lattice_vectors(points, scale, threads), counts)
    return np.mod(points[owner] + chosen / scale, 1.0)


def lattice_offsets(first, second, counts):
    """The offsets of each dot's ``counts`` children from it, nearest first, on the lattice spanned by half its
    neighbour vectors ``first`` and ``second`` shifted by a quarter of both: ``(owner, offsets)``, the children
    of dot ``c`` consecutive, in dot order. Distinct lattice points for every child: a dot with more than
    ``(2 LATTICE_REACH)²`` children takes them from a larger patch of the lattice. A dot with ``c`` > 4 children
    shrinks its lattice by ``sqrt(c / 4)``, so that they fill about its own cell, as four children do: unshrunk
    they reached into the neighbours' cells, and where neighbours had as many, children of two dots fell on the
    same points (a narrow peak: a tenth of the children on top of others)."""
    counts = np.asarray(counts, dtype=np.intp)
    owner = np.repeat(np.arange(len(first)), counts)
    within = np.arange(len(owner)) - np.repeat(np.cumsum(counts) - counts, counts)
    offsets = np.empty((len(owner), np.shape(first)[1]))
    reach = np.maximum(LATTICE_REACH, np.ceil(np.sqrt(counts) / 2)).astype(np.intp)
    for value in np.unique(reach):
        dots = reach == value
        candidates, rank = _nearest_lattice_points(first[dots], second[dots], value)
        among = np.cumsum(dots) - 1  # each selected dot's row in ``candidates``
        children = dots[owner]
        rows = among[owner[children]]
        offsets[children] = candidates[rows, rank[rows, within[children]]]
    offsets /= np.sqrt(np.maximum(counts, 4) / 4)[owner, None]
    return owner, offsets


def _nearest_lattice_points(first, second, reach):
    """The ``(2 reach)²`` lattice offsets ``((i + 1/2) first + (j + 1/2) second) / 2``, ``|i + 1/2|, |j + 1/2| <
    reach``, of each dot (``(dots, candidates, dim)``) and their order by length per dot (stable)."""
    steps = np.arange(-reach, reach) + 0.5
    i, j = (grid.ravel() for grid in np.meshgrid(steps, steps))
    offsets = (i[None, :, None] * first[:, None, :] + j[None, :, None] * second[:, None, :]) / 2
    return offsets, np.argsort(np.einsum("ijk,ijk->ij", offsets, offsets), axis=1, kind="stable")


def split_points(weights, points, n_points, scale, threads=1):
    """``n_points`` dots from the coarse ``points``: each dot's share of the mass in its cell, placed on the
    half-spacing lattice of its neighbours (see the module docstring); the children of dot ``c`` are
    consecutive, in dot order."""
    counts = shares(cell_masses(weights, points, scale, threads=threads), points, n_points)
    return lattice_children(points, counts, scale, threads)


def sphere_cell_masses(cells, points, samples_per_cell=SAMPLES_PER_CELL, threads=1):
    """``cell_masses`` on the sphere: the mass of the cell map ``cells`` (``stipple.sphere_density.CellMap``) in
    the spherical Voronoi cell of each of ``points`` (unit vectors), as fractions; every map cell is cut into
    ``f x f`` sub-cells, or on a large map cells are gathered into blocks, as ``cell_masses`` does, each of whose
    mass goes to the dot nearest to its centre."""
    block, factor = sampling_grid(cells.values.size, len(points), samples_per_cell)
    if block > 1:
        centres, sub_masses = cells.centres_and_masses(block)
    else:
        centres, sub_masses = cells.refined(factor).centres_and_masses()
    inked = sub_masses > 0
    _, owner = cKDTree(points).query(centres[inked], workers=threads)
    masses = np.bincount(owner, weights=sub_masses[inked], minlength=len(points))
    return masses / masses.sum()


def sphere_lattice_children(points, counts, threads=1):
    """``lattice_children`` on the sphere: the lattice of each dot's two neighbour vectors projected onto its
    tangent plane, each child at the end of its offset's geodesic (unit vectors)."""
    neighbours = min(7, len(points))
    _, index = cKDTree(points).query(points, k=neighbours, workers=threads)
    delta = points[index[:, 1:]] - points[:, None, :]
    delta -= np.einsum("ikj,ij->ik", delta, points)[:, :, None] * points[:, None, :]
    owner, chosen = lattice_offsets(*neighbour_pair(delta, normals=points), counts)
    return Sphere().retract(points[owner], chosen)


def split_sphere_points(cells, points, n_points, threads=1):
    """``split_points`` on the sphere: ``n_points`` unit vectors from the coarse ``points`` on the cell map
    ``cells`` (shares along a Hilbert curve through longitude and colatitude)."""
    theta, phi = spherical_angles(points)
    curve = np.stack([np.mod(phi / (2 * np.pi), 1.0), theta / np.pi], axis=1)
    counts = shares(sphere_cell_masses(cells, points, threads=threads), curve, n_points)
    return sphere_lattice_children(points, counts, threads)


def coarse_to_fine(problem, rng, *, time_limit=None, callback=None, iterations=LEVEL_ITERATIONS, smallest=None):
    """A start for ``problem`` from its coarse levels: the coarsest from its stratified start, every level
    optimised (at most ``iterations`` CG iterations, or to its ``settle``) and split into the next.

    ``problem`` needs ``level`` and ``split`` (``stipple.halftone.Problem``); returns ``problem.stratified``'s
    start where it has no levels (fewer than ``RATIO * smallest`` dots, default ``SMALLEST``). ``time_limit`` is
    for all levels; ``callback(state)`` is shown every level's states and may stop them (the points reached are
    split on).
    """
    counts = level_counts(problem.n_points, smallest=smallest)
    if not counts or problem.level is None:
        return problem.stratified(rng, problem.n_points)
    started = time.perf_counter()
    points = None
    for count in counts:
        level = problem.level(count)
        points = level.stratified(rng, count) if points is None else problem.split(points, count)
        remaining = time_left(time_limit, started)
        result = minimize(
            level.objective,
            level.manifold,
            points,
            tol=1e-6,
            max_iterations=iterations,
            time_limit=remaining,
            settle=level.settle,
            callback=callback,
        )
        points = result.points
        if result.status == "stopped":
            break
    return problem.split(points, problem.n_points)
