"""The canvas the radii are found on: the picture's own, or one that wraps around as the torus does.

A torus's dots near an edge have neighbours across the opposite edge, which fill the strip between them and
the edge. On the picture's own canvas that strip has only the near dots' discs: moved in so as not to cross the
edge (as the tone style once did), they left the outermost pixels light and the next ones dark.
A periodic canvas is the picture widened by whole cells of the analysis grid on every side, the darkness there
wrapped around and the dots copied from across the edges, so that every dot's cell, neighbours and drawn ink
are those of the torus (``stipple.render.dots.periodic_tone_dots`` draws the copies too).
"""

import numpy as np

# The periodic canvas reaches this many mean dot spacings (of the sparsest ink) beyond every edge: further than
# the cell of a dot in a region a ninth as dense as the mean; but at most this share of the picture (an ink of a
# few dots would otherwise widen the canvas to nine pictures, and the grid shrink to fit it). At half the
# picture, a colour photo's sparse black ink made the canvas four times the picture (9.0 s to draw the coffee
# photo's CMYK dots); at 0.15, 1.7 times (4.6 s), with the same CIEDE2000 to 0.01 over the picture and along its
# edges on three photos (docs/performance.md).
WRAP_SPACINGS = 3
MAX_WRAP_SHARE = 0.15
# ... but never less than this many mean spacings of all the dots: a strip a few dots high (600 x 3 px, 1500 dots) had
# a margin of 0.15 of its height, less than a spacing, its edge dots had no neighbours across the edges and grew, and
# it came out 0.028 darker on average (600 x 2: 0.034); with one spacing 0.002. (Of all the dots, not of the sparsest
# ink: a colour photo's cyan of 3 dots widened the canvas to five pictures, its command 17.7 -> 23 s and 1 GiB.)
MIN_WRAP_SPACINGS = 1


class Canvas:
    """The analysis canvas of a picture of ``size`` on the analysis ``grid``, ``margin`` grid cells ``(rows,
    columns)`` wider on every side (0: the picture's own canvas)."""

    def __init__(self, size, grid, margin=(0, 0)):
        self.picture_size = np.asarray(size, dtype=float)
        self.margin = tuple(int(m) for m in margin)
        rows, columns = grid
        cell = self.picture_size / np.array([columns, rows])
        self.offset = cell * np.array([self.margin[1], self.margin[0]])
        self.size = tuple(self.picture_size + 2 * self.offset)
        self.grid = (rows + 2 * self.margin[0], columns + 2 * self.margin[1])

    @classmethod
    def around(cls, size, grid, periodic, fewest, dots=None):
        """The picture's canvas, or (``periodic``) the one that wraps ``wrap_shares`` of the picture around it."""
        rows, columns = grid
        share_x, share_y = wrap_shares(size, periodic, fewest, dots)
        return cls(size, grid, (int(np.ceil(share_y * rows)), int(np.ceil(share_x * columns))))

    @staticmethod
    def widening(size, periodic, fewest, dots=None):
        """How many times the picture's area the canvas ``around`` it covers (before rounding to whole cells)."""
        share_x, share_y = wrap_shares(size, periodic, fewest, dots)
        return (1 + 2 * share_x) * (1 + 2 * share_y)

    def widen(self, image):
        """An image on the picture's analysis grid, ``(rows, columns[, channels])``, wrapped into the margins."""
        pads = ((self.margin[0],) * 2, (self.margin[1],) * 2) + ((0, 0),) * (np.ndim(image) - 2)
        return np.pad(image, pads, mode="wrap")

    def place(self, centres):
        """The dots (picture units) and their copies across the edges that lie in the margins, in this canvas's
        units: the dots themselves first (alone on the picture's own canvas)."""
        if not any(self.margin):
            return np.asarray(centres, dtype=float).reshape(-1, 2)
        positions, _ = wrapped_copies(centres, self.picture_size, self.offset)
        return positions + self.offset


def wrap_shares(size, periodic, fewest, dots=None):
    """``(x, y)``: the periodic canvas's margin on each side as a share of the picture's width and height,
    ``WRAP_SPACINGS`` mean spacings of ``fewest`` dots (the sparsest ink's), at most ``MAX_WRAP_SHARE`` unless
    that is less than ``MIN_WRAP_SPACINGS`` mean spacings of all the ``dots`` (default ``fewest``); ``(0, 0)`` if
    not ``periodic``, and no margin along y where ``periodic`` is "x" (an equirectangular map: longitude wraps,
    its top and bottom are the poles)."""
    if not periodic:
        return 0.0, 0.0
    width, height = size
    sparsest, mean = (np.sqrt(width * height / max(count, 1)) for count in (fewest, dots or fewest))
    # At most the whole side: the dots are copied one period across (``wrapped_copies``), and a wider margin's
    # outer part had darkness but no dots (150 dots on a 600 x 2 strip drew 0.5 gray as 0.434).
    share_x, share_y = (
        min(WRAP_SPACINGS * sparsest / extent, max(MAX_WRAP_SHARE, MIN_WRAP_SPACINGS * mean / extent), 1.0)
        for extent in (width, height)
    )
    return share_x, 0.0 if periodic == "x" else share_y


def wrapped_copies(centres, size, margin):
    """The dots and their copies across the edges of a ``size`` canvas that lie within ``margin`` (per axis) of
    it: ``(positions, origin)``, the dots themselves first, ``origin`` the index of the dot each one copies."""
    centres = np.asarray(centres, dtype=float).reshape(-1, 2)
    extent = np.asarray(size, dtype=float)
    positions, origin = [centres], [np.arange(len(centres))]
    for shift in ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)):
        moved = centres + np.array(shift) * extent
        near = np.all((moved >= -margin) & (moved < extent + margin), axis=1)
        positions.append(moved[near])
        origin.append(np.flatnonzero(near))
    return np.concatenate(positions), np.concatenate(origin)
