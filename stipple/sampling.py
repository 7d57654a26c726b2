"""Starting points drawn from a pixel image: i.i.d., or stratified along a Hilbert curve; a given start's dots at
one place parted (``part_coincident``)."""

import numpy as np


def pixel_positions(points, shape):
    """``points`` (unit coordinates, wrapped) in pixels ``(x, y)`` of an image of ``shape = (H, W)``, each in
    ``[0, W) x [0, H)``."""
    rows, columns = shape
    size = np.array([columns, rows], dtype=float)
    pixels = np.mod(points * size, size)
    pixels[pixels >= size] = 0.0  # np.mod(-1e-17, 1) == 1.0
    return pixels


def wrap_unit(values):
    """``values`` modulo 1, in ``[0, 1)``: ``np.mod(values, 1.0)`` (the same bits; a quarter of its time at a
    million points), except that a value just below a whole number, whose wrapped value rounds to 1, becomes 0."""
    wrapped = np.subtract(values, np.floor(values))
    wrapped[wrapped >= 1.0] = 0.0
    return wrapped


def pixel_indices(points, shape):
    """``(row, column)`` of the pixel of an image of ``shape = (H, W)`` that contains each of ``points`` (unit
    coordinates, wrapped)."""
    rows, columns = shape
    column = np.minimum((wrap_unit(points[:, 0]) * columns).astype(np.intp), columns - 1)
    row = np.minimum((wrap_unit(points[:, 1]) * rows).astype(np.intp), rows - 1)
    return row, column


def hilbert_index(x, y, order=16):
    """Index along the Hilbert curve of the ``2^order`` grid of integer cells ``(x, y)``."""
    side = 1 << order
    x, y = np.array(x, dtype=np.int64), np.array(y, dtype=np.int64)
    index = np.zeros(len(x), dtype=np.int64)
    s = side >> 1
    while s > 0:
        rx, ry = (x & s) > 0, (y & s) > 0
        index += s * s * ((3 * rx) ^ ry)
        flip = ~ry & rx
        x[flip], y[flip] = s - 1 - x[flip], s - 1 - y[flip]
        swap = ~ry
        x[swap], y[swap] = y[swap], x[swap].copy()
        s >>= 1
    return index


def block_sums(values, block):
    """``values`` summed over blocks of ``block x block`` cells (smaller along the last rows and columns), and each
    axis's block centres in cells: ``(sums, (row_centres, column_centres))``; the sums are ``values`` itself for a
    ``block`` of 1."""
    starts = [np.arange(0, length, block) for length in values.shape]
    centres = tuple(
        (start + np.minimum(start + block, length)) / 2 for start, length in zip(starts, values.shape, strict=True)
    )
    if block > 1:
        values = np.add.reduceat(np.add.reduceat(values, starts[0], axis=0), starts[1], axis=1)
    return values, centres


def sample_image(weights, rng, count):
    """``count`` i.i.d. points in [0, 1)² with density proportional to the pixel-constant ``weights``."""
    return _points_in_cells(weights, rng, _cells_at(weights, None, rng.random(count)))


def stratified_sample(weights, rng, count):
    """``count`` points in [0, 1)² with density ``weights``, stratified along a Hilbert curve through the pixels.

    The pixels are taken in Hilbert-curve order and point ``i`` is drawn from the ``i``-th of ``count`` equal
    slices of the mass along that order (at a uniform position inside its slice), so every stretch of the curve,
    and hence every region the curve fills, gets its share of the dots to within one. Within a pixel the position
    is uniform, so there is no lattice for the optimiser to inherit.
    """
    return _points_in_cells(weights, rng, stratified_cells(weights, rng, count))


def stratified_cells(weights, rng, count):
    """The cells (flat indices of ``weights``) of ``count`` points stratified along a Hilbert curve through the
    cells: point ``i`` in the ``i``-th of ``count`` equal slices of the mass along the curve
    (``stratified_sample``; the sphere's maps place their points in the cells themselves)."""
    rows, columns = weights.shape
    order = max(1, int(np.ceil(np.log2(max(rows, columns)))))
    fractions = (np.arange(count) + rng.random(count)) / count
    level = int(np.log2(weights.size / count) // 4)  # blocks of 4^level pixels, about sqrt(pixels / count)
    if level >= MIN_BLOCK_LEVEL:
        return _cells_through_blocks(weights, order, level, fractions)
    row, column = np.divmod(np.arange(weights.size), columns)
    along_curve = np.argsort(hilbert_index(column, row, order), kind="stable")
    return _cells_at(weights, along_curve, fractions)


# ``stratified_cells`` goes through blocks of 2^level x 2^level cells where the image has 16^level cells or more
# per point, level >= MIN_BLOCK_LEVEL (a 12-megapixel photo's 7500 coarse dots: 4.6 s through every pixel).
MIN_BLOCK_LEVEL = 2


def _cells_through_blocks(weights, order, level, fractions):
    """``stratified_cells``'s cells found in two steps, the same cells up to rounding: the Hilbert curve visits
    each aligned block of ``2^level x 2^level`` cells in one stretch, in the order of the blocks' own curve, so the
    fractions are found among the blocks' masses first, then among the cells of each block found."""
    rows, columns = weights.shape
    side = 1 << level
    padded = np.zeros((-(-rows // side) * side, -(-columns // side) * side))
    padded[:rows, :columns] = weights
    blocks = padded.reshape(padded.shape[0] // side, side, padded.shape[1] // side, side).sum(axis=(1, 3))
    block_row, block_column = np.divmod(np.arange(blocks.size), blocks.shape[1])
    along_curve = np.argsort(hilbert_index(block_column, block_row, order - level), kind="stable")
    cumulative = np.cumsum(blocks.ravel()[along_curve])
    targets = fractions * cumulative[-1]
    found = np.minimum(np.searchsorted(cumulative, targets, side="right"), blocks.size - 1)
    remainders = targets - np.where(found > 0, cumulative[found - 1], 0.0)
    block_row, block_column = np.divmod(along_curve[found], blocks.shape[1])
    return _cell_within(weights, order, side, block_row, block_column, remainders)


def _cell_within(weights, order, side, block_row, block_column, remainders):
    """Per block ``(block_row, block_column)`` of ``side x side`` cells, the flat index of the cell at which the
    block's mass, along the Hilbert curve, first passes its remainder (its last inked cell where rounding left the
    remainder at or above the block's mass)."""
    rows, columns = weights.shape
    offset_row, offset_column = np.divmod(np.arange(side * side), side)
    row = block_row[:, None] * side + offset_row[None, :]
    column = block_column[:, None] * side + offset_column[None, :]
    inside = (row < rows) & (column < columns)
    row, column = np.where(inside, row, 0), np.where(inside, column, 0)
    cells = row * columns + column
    within = np.argsort(hilbert_index(column.ravel(), row.ravel(), order).reshape(row.shape), axis=1, kind="stable")
    masses = np.take_along_axis(np.where(inside, weights[row, column], 0.0), within, axis=1)
    running = np.cumsum(masses, axis=1)
    last_inked = side * side - 1 - np.argmax(masses[:, ::-1] > 0, axis=1)
    pick = np.minimum(np.sum(running <= remainders[:, None], axis=1), last_inked)
    return np.take_along_axis(np.take_along_axis(cells, within, axis=1), pick[:, None], axis=1)[:, 0]


def _cells_at(weights, cell_order, fractions):
    """The cells (flat indices) at the given fractions of the mass, accumulated over cells in ``cell_order`` (None:
    the cells' own order)."""
    cumulative = np.cumsum(weights.ravel() if cell_order is None else weights.ravel()[cell_order])
    positions = np.minimum(np.searchsorted(cumulative, fractions * cumulative[-1], side="right"), weights.size - 1)
    return positions if cell_order is None else cell_order[positions]


def _points_in_cells(weights, rng, cells):
    rows, columns = weights.shape
    row, column = np.divmod(cells, columns)
    offsets = rng.random((len(cells), 2))
    return np.stack([(column + offsets[:, 0]) / columns, (row + offsets[:, 1]) / rows], axis=1)


# A given start's dots at one place are moved apart, the k-th after the first by PARTED_SPACING sqrt(k) mean
# spacings at k golden angles (a sunflower around the place): dots on top of each other have the same gradient in
# every objective, and no run parted them (a hostile sweep: 300 such dots ended as one on the sphere).
PARTED_SPACING = 0.5


def golden_angles(indices):
    """``indices`` times the golden angle ``pi (3 - sqrt 5)``: directions that never repeat and fill the circle
    evenly (a sunflower's), for dots that must move apart from one place (``part_coincident``, the spread step)."""
    return np.asarray(indices, dtype=float) * np.pi * (3 - np.sqrt(5))


def part_coincident(manifold, points):
    """``(points, moved)``: ``points`` with every point that repeats an earlier one (exactly) moved apart from it
    (``PARTED_SPACING``), and how many moved."""
    if not _has_repeats(points[:, 0]):
        return points, 0
    order = np.lexsort(points.T[::-1])
    ranked = points[order]
    starts = np.flatnonzero(np.r_[True, np.any(ranked[1:] != ranked[:-1], axis=1)])
    rank = np.arange(len(points)) - np.repeat(starts, np.diff(np.r_[starts, len(points)]))
    moved = order[rank > 0]
    if moved.size == 0:
        return points, 0
    rank = rank[rank > 0].astype(float)
    lengths = PARTED_SPACING * np.sqrt(manifold.area / len(points)) * np.sqrt(rank)
    points = points.copy()
    points[moved] = manifold.offset(points[moved], lengths, golden_angles(rank))
    return points, moved.size


def _has_repeats(values):
    """Whether any value repeats (a cheap first look: points that share a place share their first coordinate)."""
    ordered = np.sort(values)
    return bool(np.any(ordered[1:] == ordered[:-1]))
