"""Exact drawing of discs on a pixel grid, for the PNG writer and the tone's analysis (``stipple.tone``): a pixel
is inked where its centre lies inside a disc (strictly), so a disc's expected inked area over positions is
exactly its area, at any size."""

import numpy as np


def disc_mask(centres, radii, scale, shape):
    """The boolean image ``(rows, columns) = shape`` of the pixels whose centres lie inside a disc (strictly):
    ``centres`` and ``radii`` in canvas units, ``scale = (sx, sy)`` pixels per unit, pixel ``(i, j)`` the
    canvas's rectangle ``[j, j + 1) / sx x [i, i + 1) / sy``."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    return draw_discs(tuple(shape), centres * scale, np.asarray(radii, dtype=np.float64), tuple(scale))


def draw_discs(shape, centres, radii, scale):
    """A boolean image of ``shape`` whose pixels have their centres inside a disc; ``centres`` in pixels,
    ``radii`` in canvas units, ``scale`` = pixels per canvas unit in x and y.

    Scanlines: each disc adds +1 where its span starts on a row and -1 after it ends; the running sum along the
    row counts the discs over each pixel.
    """
    rows, columns = shape
    sx, sy = scale
    starts, stops = [], []
    reach = np.ceil(radii * sy).astype(np.int64)
    base = np.floor(centres[:, 1]).astype(np.int64)
    for k in np.unique(reach):
        chosen = np.flatnonzero(reach == k)
        offsets = np.arange(-k - 1, k + 2)
        step = max(1, (1 << 21) // len(offsets))
        for start in range(0, len(chosen), step):
            part = chosen[start : start + step]
            row = base[part, None] + offsets
            dy = (row + 0.5 - centres[part, 1:]) / sy
            half = radii[part, None] ** 2 - dy * dy
            keep = (half > 0) & (row >= 0) & (row < rows)
            half = np.sqrt(np.where(keep, half, 0.0)) * sx
            x = np.broadcast_to(centres[part, :1], half.shape)
            first = np.floor(x - half - 0.5).astype(np.int64) + 1
            last = np.ceil(x + half - 0.5).astype(np.int64) - 1
            first, last = np.maximum(first, 0), np.minimum(last, columns - 1)
            keep &= first <= last
            line = row[keep] * (columns + 1)
            starts.append(line + first[keep])
            stops.append(line + last[keep] + 1)
    size = rows * (columns + 1)
    ends = np.zeros(size, dtype=np.int32)
    for marks, sign in ((starts, 1), (stops, -1)):
        if not marks:
            continue
        marks = np.concatenate(marks)
        if size <= 1 << 22:
            ends += sign * np.bincount(marks, minlength=size).astype(np.int32)
        else:  # a large canvas: counting the marked pixels only is cheaper than a canvas-sized count
            index, counts = np.unique(marks, return_counts=True)
            ends[index] += sign * counts.astype(np.int32)
    covered = np.cumsum(ends.reshape(rows, columns + 1), axis=1, dtype=np.int32)[:, :columns] > 0
    return covered
