"""Radii whose drawn union covers each dot's Voronoi cell to its darkness (see ``stipple.tone``)."""

import numpy as np
from PIL import Image
from scipy import ndimage
from scipy.spatial import cKDTree

from ..errors import StippleError
from .checks import check_colours, check_darkness, check_discs, check_options, check_size
from .inks import multiply_colour
from .raster import MAX_GRID_PIXELS, union_coverage_image
from .wrap import Canvas

SATURATION = 9.55
FULL = 0.999
# Fine pixels per analysis-grid pixel along each axis where the grid leaves room (``analysis_supersample``): at 2
# a light tone's dot, a grid pixel across, was drawn a fine pixel or two off and the corrections fitted that noise
# (a flat 0.97 page's radii 10 % apart); 4 drew held-out photos 10-40 % closer at sigma 4 px (docs/picture.md).
# Only the drawings that the last FINE_PASSES corrections read need it: the same pictures, the drawing's time of 2.
ANALYSIS_SUPERSAMPLE, COARSE_SUPERSAMPLE, FINE_PASSES = 4, 2, 2
SAMPLES_PER_DOT = 24
STEP_BOUNDS = (0.5, 2.0)
REGULARISATION = 0.003
COLOUR_PASSES = 6
DAMPING = 0.7


def union_coverage(ratio):
    """Fraction of the paper that blue-noise discs cover at the ink ratio ``x = density * pi r^2``.

    Parameters
    ----------
    ratio : float or numpy.ndarray
        The ink ratio ``x >= 0``: the discs' total area over the paper's, counting overlaps twice.

    Returns
    -------
    numpy.ndarray
        ``f(x) = x (1 + x^n)^(-1/n)`` with ``n = SATURATION``: ``x`` while the discs are apart, tending to 1.
    """
    x = np.asarray(ratio, dtype=np.float64)
    if np.any(~np.isfinite(x)) or np.any(x < 0):
        raise StippleError("ratio must be finite and >= 0")
    return x * (1.0 + x**SATURATION) ** (-1.0 / SATURATION)


def ink_ratio(coverage):
    """The ink ratio at which blue-noise discs cover ``coverage`` of the paper (``union_coverage``'s inverse).

    Parameters
    ----------
    coverage : float or numpy.ndarray
        Covered fraction in [0, 1]; values above ``FULL`` (0.999) are taken as ``FULL``.

    Returns
    -------
    numpy.ndarray
        ``x = f / (1 - f^n)^(1/n)``.
    """
    f = np.asarray(coverage, dtype=np.float64)
    if np.any(~np.isfinite(f)) or np.any(f < 0) or np.any(f > 1):
        raise StippleError("coverage must be in [0, 1]")
    f = np.minimum(f, FULL)
    return f / (1.0 - f**SATURATION) ** (1.0 / SATURATION)


def tone_radii(
    centres,
    darkness,
    size,
    *,
    passes=4,
    min_radius=0.0,
    max_radius=None,
    max_ratio=1.0,
    samples_per_dot=SAMPLES_PER_DOT,
    periodic=False,
):
    """Radii that make the union of the discs cover the darkness of the image: dark regions come out dark.

    Parameters
    ----------
    centres : numpy.ndarray
        ``(N, 2)`` dot centres ``(x, y)`` in canvas units (x right, y down), inside the canvas.
    darkness : numpy.ndarray
        ``(H, W)`` target ink coverage in [0, 1] stretched over the canvas (row 0 at the top): for a torus
        stipple, the density ``w`` the dots were placed from (``1 - luminance`` for a gray image).
    size : (float, float)
        The canvas's ``(width, height)`` in the units of ``centres``.
    passes : int
        Corrections against the drawn union (0 to 50); 0 keeps the model's first estimate.
    min_radius : float
        Smallest radius (>= 0), e.g. a pen's or printer's smallest dot.
    max_radius : float, optional
        Largest radius (> 0; default: none but ``max_ratio``'s).
    max_ratio : float
        Largest radius over the distance to the nearest other dot, in (0, 10]: 1 lets a dot reach its nearest
        neighbour's centre, enough to fill black (blue noise fills the paper at about 0.7).
    samples_per_dot : int
        Analysis grid pixels per dot on average (4 to 1024), and at least half as many per dot where the dots
        are densest (``_grid``); the cost grows with it.
    periodic : bool
        The canvas wraps around, as the torus the dots were placed on: the dots across each edge are the
        neighbours of the dots near it, and their discs (drawn across the edge too) ink the strip between
        them (``stipple.tone.wrap``).

    Returns
    -------
    numpy.ndarray
        ``(N,)`` radii in canvas units.

    Notes
    -----
    See ``stipple.tone``'s docstring. Each dot's ink is matched within its own Voronoi cell; a dot whose cell has no
    grid pixel (two dots in one pixel) takes the radius of the dot that has the pixel.
    """
    centres, _ = check_discs(centres, None)
    size = check_size(size)
    darkness = check_darkness(darkness)
    passes, samples_per_dot, bounds = check_options(passes, samples_per_dot, min_radius, max_radius, max_ratio)
    if len(centres) == 0:
        return np.zeros(0)
    dots = len(centres) * max(1.0, densest_ratio(centres, darkness, size) / 2)
    grid, canvas = _analysis_canvas(size, dots, samples_per_dot, periodic, len(centres))
    ink = _Ink(canvas.place(centres), canvas.size, canvas.grid, canvas.widen(_resample(darkness, grid)), bounds)
    for index in range(passes):
        ink.correct(ink.target, fine=index >= passes - FINE_PASSES)
    return ink.final()[: len(centres)]


def tone_radii_layers(
    layers,
    size,
    *,
    colours=None,
    target=None,
    passes=None,
    min_radius=0.0,
    max_radius=None,
    max_ratio=1.0,
    max_ratio_any=2.0,
    samples_per_dot=SAMPLES_PER_DOT,
    periodic=False,
):
    """Tone-true radii for several inks: alone, or printed over each other with multiply blending.

    Parameters
    ----------
    layers : list of (numpy.ndarray, numpy.ndarray)
        ``(centres, coverage)`` per ink: the ink's dot centres ``(N_k, 2)`` in canvas units and its target
        coverage ``(H, W)`` in [0, 1] over the canvas (``multiply_separation``), all of one shape.
    size : (float, float)
        The canvas's ``(width, height)``.
    colours : list of tuple, optional
        Each ink's colour (RGB in [0, 1]). Without it, each ink's dots cover its own coverage image, whatever
        the other inks do (``tone_radii`` per ink). With it, the inks are drawn together, multiplied on white
        paper, and corrected so that the drawing's colour matches ``target`` (see Notes).
    target : numpy.ndarray, optional
        ``(H, W, 3)`` colour in [0, 1] to print (with ``colours``; default: ``multiply_colour`` of the layers'
        coverages, the colour they print when laid independently; for ``multiply_separation``, the image).
    passes : int, optional
        Correction passes, as for ``tone_radii``; default 4 for inks alone, ``COLOUR_PASSES`` (6) with
        ``colours``: the joint correction converges more slowly where one ink shows only between another's
        dots (a dark blue drawn with black, cyan and magenta reached 0.84 of its chroma after 4, 0.855 after 6).
    min_radius, max_radius, max_ratio, samples_per_dot, periodic :
        As for ``tone_radii``; ``max_ratio`` applies to each ink's own spacing.
    max_ratio_any : float
        With ``colours``: largest radius over the distance to the nearest dot of any ink, in (0, 10]. A sparse
        ink's dot in a region that another ink covers (a stray cyan dot in black) would otherwise grow over its
        whole, large, cell to mend the last percent of the colour under the other ink's dots.

    Returns
    -------
    list of numpy.ndarray
        The radii of each layer's dots.

    Notes
    -----
    Dots of different inks are not laid independently (the joint optimisation keeps them apart where they
    are sparse), so neither "coverages add" (``stipple.colour.separate``) nor "coverages multiply"
    (``multiply_colour``) predicts the drawn colour. The correction does not predict it: each pass draws every
    ink on the analysis grid, ``R = prod_k (1 - a_k (1 - p_k))`` (``a_k`` the covered fraction of a grid pixel,
    a fifth of a dot's spacing across), and, ink after ink (each seeing the others' latest drawing),
    changes each dot's coverage within its cell by the least-squares step that moves the cell's mean colour to
    the target's: ``d = (R* - R) . g / (g . g + 0.003)`` with ``g = -(1 - p_k) * mean(prod_{j != k} ...)``, the
    colour's rate of change with the ink's coverage there (small where other inks already absorb everything,
    so an ink under black keeps its coverage), then steps the radius to the new coverage through the model.
    """
    if not isinstance(layers, list | tuple) or not all(isinstance(x, list | tuple) and len(x) == 2 for x in layers):
        raise StippleError("layers must be a list of (centres, coverage) pairs")
    if passes is None:
        passes = 4 if colours is None else COLOUR_PASSES
    if colours is None:
        options = dict(min_radius=min_radius, max_radius=max_radius, max_ratio=max_ratio, periodic=periodic)
        return [tone_radii(c, a, size, passes=passes, samples_per_dot=samples_per_dot, **options) for c, a in layers]
    size = check_size(size)
    passes, samples_per_dot, bounds = check_options(passes, samples_per_dot, min_radius, max_radius, max_ratio)
    if not (np.isfinite(max_ratio_any) and 0 < max_ratio_any <= 10):
        raise StippleError(f"max_ratio_any must be in (0, 10], not {max_ratio_any!r}")
    checked = [(check_discs(c, None)[0], check_darkness(a, "coverage")) for c, a in layers]
    shapes = {a.shape for _, a in checked}
    if len(shapes) > 1:
        raise StippleError(f"layers' coverages must all have one shape, not {sorted(shapes)}")
    absorb = check_colours(colours, len(checked))
    if target is None:
        target = multiply_colour([a for _, a in checked], colours)
    target = np.asarray(target, dtype=np.float64)
    if target.shape != (*next(iter(shapes)), 3) or not np.all(np.isfinite(target)):
        raise StippleError(
            f"target must be a finite (H, W, 3) colour image of the coverages' shape, not {target.shape}"
        )
    if target.min() < 0 or target.max() > 1:
        raise StippleError("target colour values must be in [0, 1]")
    total = sum(len(c) for c, _ in checked)
    if total == 0:
        return [np.zeros(0) for _ in checked]
    canvas, grid, inks = _joint_inks(checked, size, samples_per_dot, bounds, max_ratio_any, periodic)
    # A correction reads the drawings made in the pass before: fine for the last FINE_PASSES corrections.
    drawn = [ink.draw(passes <= FINE_PASSES) if ink else np.zeros(canvas.grid, np.float32) for ink in inks]
    channels = [np.flatnonzero(a > 0) for a in absorb]
    goal = {
        ch: canvas.widen(_resample(target[..., ch], grid)).astype(np.float32) for ch in set().union(*map(set, channels))
    }
    goals = [{ch: ink.mean(goal[ch]) for ch in chans} if ink else {} for ink, chans in zip(inks, channels, strict=True)]
    for index in range(passes):
        for k, ink in enumerate(inks):
            if ink is None or not len(channels[k]):
                continue
            step, norm = np.zeros(len(ink.count)), np.zeros(len(ink.count))
            for ch in channels[k]:
                others = np.ones(canvas.grid, np.float32)
                for j, image in enumerate(drawn):
                    if j != k and absorb[j, ch] > 0:
                        others *= 1.0 - np.float32(absorb[j, ch]) * image
                colour = others * (1.0 - np.float32(absorb[k, ch]) * drawn[k])
                slope = -absorb[k, ch] * ink.mean(others)
                step += (goals[k][ch] - ink.mean(colour)) * slope
                norm += slope * slope
            ink.correct(np.clip(ink.covered + step / (norm + REGULARISATION), 0.0, 1.0))
            drawn[k] = ink.draw(index >= passes - FINE_PASSES - 1)
    return [ink.final()[: len(c)] if ink else np.zeros(0) for ink, (c, _) in zip(inks, checked, strict=True)]


def _joint_inks(checked, size, samples_per_dot, bounds, max_ratio_any, periodic):
    """``(canvas, grid, inks)`` for ``tone_radii_layers``' joint correction: one analysis grid for all inks (the
    picture's ``grid``, widened on a periodic ``canvas``), an ``_Ink`` per ink with dots (None without), each dot's
    radius capped at ``max_ratio_any`` times the distance to the nearest dot of any ink."""
    total = sum(len(c) for c, _ in checked)
    # Every ink's densest dots get half the average's share of the grid: an ink of few dots, dense in one place,
    # asks for as many pixels as its own dots there need, not as all the dots would at its density.
    dots = max(total, max(len(c) * densest_ratio(c, a, size) / 2 for c, a in checked if len(c)))
    fewest = min(len(c) for c, _ in checked if len(c))
    grid, canvas = _analysis_canvas(size, dots, samples_per_dot, periodic, fewest)
    placed = [canvas.place(c) for c, _ in checked]
    inks = [
        _Ink(p, canvas.size, canvas.grid, canvas.widen(_resample(a, grid)), bounds) if len(c) else None
        for p, (c, a) in zip(placed, checked, strict=True)
    ]
    if total > 1:
        everything = np.concatenate(placed)
        for ink, p in zip(inks, placed, strict=True):
            if ink is not None:
                nearest = nearest_elsewhere(p, everything)
                ink.cap = np.maximum(np.minimum(ink.cap, max_ratio_any * nearest), ink.min_radius)
                ink.floor = np.minimum(ink.floor, ink.cap)
                ink.radii = ink.bounded(ink.radii)
    return canvas, grid, inks


def fit_inside(layers, size, *, how="clamp", margin=None):
    """Dots moved so that none crosses the canvas's edge, without changing the tone.

    Parameters
    ----------
    layers : list of (numpy.ndarray, numpy.ndarray)
        ``(centres, radii)`` per layer in canvas units.
    size : (float, float)
        The canvas's ``(width, height)``.
    how : {"clamp", "scale"}
        "clamp": each dot that would cross an edge moves inwards just enough (less than its radius); every
        other dot stays where it was placed, so the picture stays registered with the image. "scale": the
        centres are mapped affinely onto the canvas shrunk by ``margin`` on every side, as
        ``stipple.render.dots.inset`` does, and the radii scaled by the same factor, so that the dots' ink keeps its
        share (moving the centres only packs them denser: darker by about ``4 margin / width``).
    margin : float, optional
        "scale" only: the inset on every side (>= 0; default: the largest radius).

    Returns
    -------
    tuple
        ``(layers, margin)``: the centres and radii per layer, and the margin used ("clamp": 0; "scale": at most
        a quarter of the shorter side, as in ``stipple.render.dots.inset``).
    """
    width, height = check_size(size)
    checked = [check_discs(centres, radii) for centres, radii in layers]
    if how == "clamp":
        extent = np.array([width, height])
        moved = []
        for centres, radii in checked:
            r = np.minimum(radii, 0.5 * extent.min())[:, None]
            moved.append((np.clip(centres, r, extent - r), radii))
        return moved, 0.0
    if how != "scale":
        raise StippleError(f"how must be one of clamp, scale, not {how!r}")
    if margin is None:
        margin = max([float(radii.max()) for _, radii in checked if len(radii)] + [0.0])
    if not (np.isfinite(margin) and margin >= 0):
        raise StippleError(f"margin must be a finite number >= 0, not {margin!r}")
    margin = min(float(margin), 0.25 * min(width, height))
    shrink = np.array([(width - 2 * margin) / width, (height - 2 * margin) / height])
    factor = float(np.sqrt(shrink.prod()))
    return [(margin + centres * shrink, radii * factor) for centres, radii in checked], margin


class _Ink:
    """One ink's dots on the analysis grid: Voronoi cells, their areas and targets, bounds and radii."""

    def __init__(self, centres, size, grid, darkness, bounds):
        rows, columns = grid
        width, height = size
        self.centres, self.size, self.grid = centres, size, grid
        row, column = canvas_pixels(centres, size, grid)
        flat = row * columns + column
        owner_of_pixel = np.full(rows * columns, -1, dtype=np.int64)
        owner_of_pixel[flat] = np.arange(len(centres))
        self.owner = owner_of_pixel[flat]  # the dot that keeps each dot's pixel (itself, or one sharing it)
        seeds = owner_of_pixel.reshape(rows, columns) < 0
        nearest = ndimage.distance_transform_edt(seeds, return_distances=False, return_indices=True)
        self.labels = owner_of_pixel.reshape(rows, columns)[nearest[0], nearest[1]].ravel()
        count = np.bincount(self.labels, minlength=len(centres)).astype(np.float64)
        self.count = np.maximum(count, 1.0)
        area = count * (width / columns) * (height / rows)
        self.target = np.clip(self.mean(darkness), 0.0, 1.0)
        min_radius, max_radius, max_ratio = bounds
        self.min_radius = min_radius
        self.cap = np.maximum(_cap(centres, max_radius, max_ratio), min_radius)
        self.floor = np.minimum(np.maximum(min_radius, 1e-3 * np.sqrt(width * height / len(centres))), self.cap)
        self.radii = self.bounded(np.sqrt(ink_ratio(self.target) * area / np.pi))
        self.drawn = self.covered = None

    def mean(self, image):
        """Each cell's mean of an image on the grid (``(N,)``, or ``(N, C)`` for ``C`` channels)."""
        if image.ndim == 2:
            return np.bincount(self.labels, weights=image.ravel(), minlength=len(self.count)) / self.count
        flat = image.reshape(-1, image.shape[-1])
        return np.stack([self.mean(flat[:, k].reshape(self.grid)) for k in range(flat.shape[1])], axis=1)

    def bounded(self, radii):
        """Radii within the dots' bounds; dots without a cell take their pixel owner's radius."""
        return np.clip(radii[self.owner], self.floor, self.cap)

    def draw(self, fine=True):
        """The union of the discs on the grid (``fine``, or ``COARSE_SUPERSAMPLE``) and each cell's covered fraction."""
        supersample = analysis_supersample(self.grid, ANALYSIS_SUPERSAMPLE if fine else COARSE_SUPERSAMPLE)
        self.drawn = union_coverage_image(self.centres, self.radii, self.size, self.grid, supersample=supersample)
        self.covered = np.clip(self.mean(self.drawn), 0.0, 1.0)
        return self.drawn

    def correct(self, wanted, fine=True):
        """Step each radius towards the coverage ``wanted`` in its cell: ``(f^-1(wanted) / f^-1(c))^(DAMPING / 2)``
        (``c`` from the latest drawing, or a new one, ``fine`` or not)."""
        if self.covered is None:
            self.draw(fine)
        with np.errstate(divide="ignore", invalid="ignore"):
            factor = np.sqrt(ink_ratio(wanted) / ink_ratio(self.covered))
        factor = np.where(self.covered > 0, factor, STEP_BOUNDS[1])
        factor = np.where((self.covered > 0) & (wanted <= 0), STEP_BOUNDS[0], factor)
        factor = np.clip(np.nan_to_num(factor, nan=1.0), *STEP_BOUNDS)
        self.radii = self.bounded(self.radii * factor**DAMPING)
        self.drawn = self.covered = None

    def final(self):
        """The radii, at least ``min_radius`` (the working floor is a little above 0, so that dots can grow)."""
        return np.clip(self.radii, self.min_radius, self.cap)


def analysis_supersample(grid, most=ANALYSIS_SUPERSAMPLE):
    """``most``, or fewer where the fine pixels would pass the drawing's bound (``check_picture``)."""
    rows, columns = grid
    return max(1, min(most, int(np.sqrt(4 * MAX_GRID_PIXELS / (rows * columns)))))


def canvas_pixels(centres, size, shape):
    """``(row, column)`` of the pixel of an image of ``shape = (rows, columns)`` stretched over a canvas of
    ``size = (width, height)`` that holds each of ``centres`` (canvas units; those beyond an edge: its nearest)."""
    rows, columns = shape
    width, height = size
    column = np.clip((centres[:, 0] * columns / width).astype(np.int64), 0, columns - 1)
    row = np.clip((centres[:, 1] * rows / height).astype(np.int64), 0, rows - 1)
    return row, column


def densest_ratio(centres, darkness, size):
    """How much denser than on average the densest dots are: the 99th percentile of the darkness at the dots
    over the darkness's mean (the torus places dots in proportion to it)."""
    at_dots = darkness[canvas_pixels(centres, size, np.shape(darkness))]
    return float(np.percentile(at_dots, 99) / max(float(np.mean(darkness)), 1e-12))


def _analysis_canvas(size, dots, samples_per_dot, periodic, fewest):
    """``(grid, canvas)``: the picture's analysis grid of ``samples_per_dot`` pixels for each of ``dots`` and the
    canvas around it (``Canvas.around``), the grid made smaller where the canvas would pass ``MAX_GRID_PIXELS``
    (a million dots' grid was at that bound, and its widened canvas could not be drawn).

    The callers count the densest dots as more than one: the average share alone left the dots of a few small
    dark marks on a light page (28 times as dense there) a pixel each, their coverage measured too coarsely, and a
    6-pixel mark of luminance 0.05 came out 0.17 at its core (0.05 at half the average's share for the densest
    dots: sigma 4 px RMSE 0.0040 -> 0.0027, the darkest tenth 0.061 -> 0.021).
    """
    room = 0.98 * MAX_GRID_PIXELS / Canvas.widening(size, periodic, fewest, dots)  # 2 % for the margins' cells
    grid = _grid(size, min(samples_per_dot * dots, room))
    return grid, Canvas.around(size, grid, periodic, fewest, dots)


def _grid(size, pixels):
    """``(rows, columns)`` of about ``pixels`` square pixels over a canvas of ``size``."""
    width, height = size
    step = np.sqrt(width * height / pixels)
    return max(int(round(height / step)), 1), max(int(round(width / step)), 1)


def _resample(darkness, grid):
    """The darkness on the analysis grid, area-averaged (Pillow's box filter)."""
    rows, columns = grid
    image = Image.fromarray(darkness.astype(np.float32), "F")
    if image.size != (columns, rows):
        image = image.resize((columns, rows), Image.Resampling.BOX)
    return np.clip(np.asarray(image, dtype=np.float64), 0.0, 1.0)


def _cap(centres, max_radius, max_ratio, nearest=None):
    """Each dot's largest radius: ``max_ratio`` times the distance to its nearest other dot, at most
    ``max_radius``. Dots at one place count as one (their nearest other dot is the nearest elsewhere)."""
    if nearest is None:
        nearest = nearest_elsewhere(centres, centres)
    return np.minimum(max_ratio * nearest, np.inf if max_radius is None else max_radius)


def nearest_elsewhere(points, centres, neighbours=8):
    """Distance from each point to the nearest of ``centres`` not at the same place (``inf`` if none)."""
    if len(centres) < 2:
        return np.full(len(points), np.inf)
    k = min(neighbours, len(centres))
    distances, _ = cKDTree(centres).query(points, k=k)
    distances = distances.reshape(len(points), k)
    extent = np.ptp(centres, axis=0).max() if len(centres) else 0.0
    apart = distances > 1e-9 * max(extent, 1e-300)
    first = np.where(apart.any(axis=1), np.argmax(apart, axis=1), 0)
    return np.where(apart.any(axis=1), distances[np.arange(len(points)), first], np.inf)
