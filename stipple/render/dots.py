"""Geometry of drawn dots: radii that keep the tone without letting neighbours touch, an inset that keeps every
dot inside the canvas, and foreshortened dots on the orthographic globe.

The default radius of a dot is ``min(r_tone, TOUCH_FRACTION * d)``, ``d`` its distance to its nearest
neighbour on the drawing: ``r_tone`` (``pi r^2 M = ink area``) keeps the tone wherever the dots are far enough
apart, and two dots ``i, j`` never touch, since ``r_i + r_j <= 0.9 max(d_i, d_j) <= 0.9 |p_i - p_j|``.
"""

import heapq
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from ..errors import StippleError
from ..io.png import float_picture_layers, picture_channels
from ..nearfield import check_pair_memory
from ..tone import fit_inside, tone_radii_layers
from ..tone.radii import canvas_pixels
from ..tone.wrap import wrapped_copies

TOUCH_FRACTION = 0.45
MIN_SQUASH = 0.02
# A copy of a dot across a periodic picture's edge is not drawn where the picture wants less than this share of
# the ink that its other copies' places want (``wanted_copies``).
UNWANTED_SHARE = 0.25
# ... but only where the picture is near white there: below NEAR_WHITE coverage. A light gray edge (0.05) across
# from a dark one (0.7) lost its copies' ink and the dots drawn across the edge instead, which the radii had
# counted: its outermost pixels came out 25 % too light (a scanned page's right edge +0.038 in luminance, +0.007
# inside; the portrait's sigma 4 px RMSE 0.0044 against 0.0035 with them).
NEAR_WHITE = 0.02
# The largest inset from a flat page's edges, over its shorter side (``inset``); a pen whose smallest dots need
# more is refused (``flat_dots``).
MAX_MARGIN = 0.25
# How far the smallest pen dot of each style inks from its centre on its widest side, in pens (``pen_extent``): a
# "point" is a stroke a tenth of the pen long, half the pen around it (0.6 of the pen on the stroke's side); the
# smallest "circle" a ring of radius pen / 20 (0.55); the smallest "filled" dot the point's stroke (0.6).
PEN_EXTENTS = {"point": 0.6, "circle": 0.55, "filled": 0.6}


@dataclass
class Dots:
    """One layer of dots in canvas user units.

    ``radii`` are per dot; a foreshortened dot is an ellipse whose axis along ``angle`` (radians, canvas
    coordinates, y down) is ``squash`` times its radius; ``paths`` are pen paths (``stipple.render.pen``), if any.
    ``copies``, ``(centres, radii)``: on a page that wraps around (a torus's tone picture), the discs' copies
    across its edges, drawn by the PNG and the SVG (circles of class "copy") too, cut by the page. ``kept``: which
    of the layer's given dots these are, where a pen's dots were thinned (``flat_dots``); None for all.
    """

    name: str
    colour: tuple
    centres: np.ndarray
    radii: np.ndarray
    squash: np.ndarray | None = None
    angle: np.ndarray | None = None
    paths: list | None = None
    copies: tuple | None = None
    kept: np.ndarray | None = None


def nearest_distances(points):
    """Distance from each row of ``points`` to its nearest other row (``inf`` for a single point; 0 for a row
    given more than once). The tree holds each position once: 5 million copies of one point in a CSV kept
    ``stipple render`` searching for over 10 minutes, deaf to SIGTERM."""
    points = np.asarray(points, dtype=np.float64)
    positions, where, copies = np.unique(points, axis=0, return_inverse=True, return_counts=True)
    distances = np.full(len(positions), np.inf)
    if len(positions) > 1:
        distances = cKDTree(positions).query(positions, k=2)[0][:, 1]
    return np.where(copies > 1, 0.0, distances)[where.ravel()]


def capped_radii(distances, tone_radius, fraction=TOUCH_FRACTION):
    """Per-dot radii ``min(tone_radius, fraction * distances)`` (see the module's docstring)."""
    return np.minimum(float(tone_radius), fraction * np.asarray(distances, dtype=np.float64))


def inset(centres, size, margin, least=0.0):
    """Positions on a ``size = (width, height)`` canvas mapped affinely onto the canvas shrunk by ``margin`` on
    every side, so that a dot of radius up to ``margin`` stays inside (at most ``MAX_MARGIN`` of the shorter
    side: the radii are capped there). ``least``: what every dot inks however small its radius (a pen's smallest
    dot, ``pen_extent``), refused past that bound, where the inset stops (a 500 mm pen inked far past a 300-unit
    page)."""
    extent = np.asarray(size, dtype=np.float64)
    check_pen_fits(least, extent, "its dots ink")
    margin = capped_margin(margin, size)
    return margin + np.asarray(centres) * (extent - 2 * margin) / extent, margin


def capped_margin(margin, size):
    """``margin`` at most ``MAX_MARGIN`` of the shorter side of a ``size = (width, height)`` canvas."""
    return min(float(margin), MAX_MARGIN * min(size))


def check_pen_fits(reach, extent, what):
    """Refuse a pen that inks ``reach`` units from where it is placed (``what`` says how) when that is more than
    ``MAX_MARGIN`` of the page's shorter side (``extent``, its width and height)."""
    if reach > MAX_MARGIN * min(extent):
        raise StippleError(
            f"the pen is too wide for the page: {what} {reach:.4g} units from their centres, more than "
            f"{MAX_MARGIN:g} of the page's shorter side ({min(extent):.4g}); give a narrower --pen-width or a "
            "larger --width"
        )


def flat_dots(layers, size, tone_radius=None, radius=None, pen=None, dot_style=None):
    """``Dots`` of layers ``(name, colour, centres)`` on a flat canvas, inset so that none crosses its edge.

    With ``radius`` every dot has it; otherwise radii are capped from the spacing of all layers' dots together
    (``capped_radii`` of ``tone_radius``). ``pen`` (a stroke width) and ``dot_style``, for pen-drawn dots: the
    margin is at least the smallest dot's ink (``pen_extent``), and without ``radius`` the dots are first thinned
    (``thin_apart``, all layers together) to ``least_pen_reach / TOUCH_FRACTION``, closer than which they would
    touch however small their radii; the layers hold only the dots kept.
    """
    if pen is not None and dot_style not in PEN_EXTENTS:
        raise ValueError(f"dot_style must be one of {', '.join(PEN_EXTENTS)} with a pen, not {dot_style!r}")
    least = 0.0 if pen is None else pen_extent(dot_style, pen)
    margin = max(radius if radius is not None else tone_radius, least)
    placed = []
    for name, colour, centres in layers:
        moved, margin_used = inset(centres, size, margin, least)
        placed.append((name, colour, moved))
    if radius is not None:
        return [Dots(name, colour, c, np.full(len(c), float(radius))) for name, colour, c in placed]
    everything = np.concatenate([c for _, _, c in placed]) if placed else np.zeros((0, 2))
    kept = np.ones(len(everything), dtype=bool)
    if pen is not None:
        kept = thin_apart(everything, least_pen_reach(dot_style, pen) / TOUCH_FRACTION)
    radii = np.zeros(len(everything))
    radii[kept] = np.minimum(capped_radii(nearest_distances(everything[kept]), tone_radius), margin_used)
    ends = np.cumsum([len(c) for _, _, c in placed])
    layers = []
    for (name, colour, centres), end in zip(placed, ends, strict=True):
        own = slice(end - len(centres), end)
        layers.append(Dots(name, colour, centres[kept[own]], radii[own][kept[own]], kept=kept[own]))
    return layers


def left_out_note(left_out, of, where=""):
    """The line that says ``left_out`` dots of ``of`` ("6000 dots", "the 2725 dots shown") were left out of a pen
    drawing where they would touch (``thin_apart``), ``where`` saying where."""
    return f"{left_out} of {of} left out where the pen's dots would touch{where}"


def least_pen_reach(dot_style, pen):
    """How far the smallest pen dot of ``dot_style`` reaches towards a neighbour, for a pen ``pen`` wide: its
    ``pen_extent``, but half the pen for a "point", whose short stroke turns any way (two points the no-touch
    distance ``pen / 2 / TOUCH_FRACTION`` apart still leave a hundredth of the pen between them)."""
    return 0.5 * pen if dot_style == "point" else pen_extent(dot_style, pen)


def pen_extent(dot_style, pen):
    """How far the smallest pen dot of ``dot_style`` inks from its centre on its widest side (``PEN_EXTENTS``):
    the margin it needs at the page's edge. Until 2026-11-27 the margin was half the pen, and such dots crossed
    the page's edge."""
    return PEN_EXTENTS[dot_style] * pen


def thin_dots(dots, distance):
    """``dots`` (one layer, no paths yet) without the dots that ``thin_apart`` leaves out at ``distance``, and how
    many it left out."""
    kept = thin_apart(dots.centres, distance)
    keep = {name: None if value is None else value[kept] for name, value in vars(dots).items() if name in THINNED}
    return Dots(dots.name, dots.colour, **keep, kept=kept), int((~kept).sum())


# The per-dot fields of ``Dots`` that ``thin_dots`` subsets.
THINNED = ("centres", "radii", "squash", "angle")


def thin_apart(centres, distance):
    """A mask of ``centres`` no two of which are closer than ``distance``: while any two are, the dot with the most
    such neighbours left is left out (the lowest index among equals), which keeps more dots in a dense cluster
    than taking the dots in turn. Every dot left out has a kept dot within ``distance``. Copies of one position
    are always too close: the last of them stands for them all (their pairs grew as the square of their count),
    and points too clumped for their pairs to fit in memory are refused (``check_pair_memory``)."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    kept = np.zeros(len(centres), dtype=bool)
    last = np.sort(len(centres) - 1 - np.unique(centres[::-1], axis=0, return_index=True)[1])  # in their order
    kept[last[_thin_distinct(centres[last], distance)]] = True
    return kept


def _thin_distinct(centres, distance):
    """``thin_apart`` of distinct ``centres``."""
    pairs = np.zeros((0, 2), dtype=np.intp)
    if len(centres) > 1:
        tree = cKDTree(centres)
        check_pair_memory(tree, centres, distance)
        pairs = tree.query_pairs(distance, output_type="ndarray")
    kept = np.ones(len(centres), dtype=bool)
    if len(pairs) == 0:
        return kept
    both = np.concatenate([pairs, pairs[:, ::-1]])
    both = both[np.argsort(both[:, 0], kind="stable")]
    starts = np.searchsorted(both[:, 0], np.arange(len(centres) + 1))
    degree = np.diff(starts)
    queue = [(-int(degree[dot]), int(dot)) for dot in np.flatnonzero(degree)]
    heapq.heapify(queue)
    while queue:
        negative, dot = heapq.heappop(queue)
        if not kept[dot] or -negative != degree[dot] or degree[dot] == 0:
            continue
        kept[dot] = False
        for neighbour in both[starts[dot] : starts[dot + 1], 1]:
            if kept[neighbour]:
                degree[neighbour] -= 1
                heapq.heappush(queue, (-int(degree[neighbour]), int(neighbour)))
    for dot in np.flatnonzero(~kept):  # a dot whose too-close neighbours all went after it comes back
        if not kept[both[starts[dot] : starts[dot + 1], 1]].any():
            kept[dot] = True
    return kept


def tone_dots(layers, size, coverages, *, target=None, periodic=False):
    """Tone-true ``Dots``: radii (``stipple.tone``) that make the drawn ink reproduce ``coverages``.

    Parameters
    ----------
    layers : list of (str, tuple, numpy.ndarray)
        ``(name, colour, centres)`` per ink, centres in canvas units.
    size : (float, float)
        The canvas's ``(width, height)``.
    coverages : list of numpy.ndarray
        Each ink's target coverage ``(H, W)`` in [0, 1] over the canvas (for one ink, the density ``w``).
    target : numpy.ndarray, optional
        ``(H, W, 3)`` colour the inks, multiplied on white paper, must print; then the inks are corrected
        together against the drawn colour (``stipple.tone.tone_radii_layers``), otherwise each alone.
    periodic : bool or "x"
        The canvas wraps around, as the torus the dots were placed on (``periodic_tone_dots``), or along x only
        (an equirectangular map). Otherwise dots that would cross the canvas's edge move inwards just enough
        (``fit_inside``, "clamp"): the picture stays registered with the image.
    """
    if periodic:
        return periodic_tone_dots(layers, size, coverages, target=target, axes=periodic)
    pairs = [(centres, coverage) for (_, _, centres), coverage in zip(layers, coverages, strict=True)]
    colours = None if target is None else [colour for _, colour, _ in layers]
    radii = tone_radii_layers(pairs, size, colours=colours, target=target)
    placed, _ = fit_inside([(c, r) for (c, _), r in zip(pairs, radii, strict=True)], size, how="clamp")
    return [Dots(name, colour, c, r) for (name, colour, _), (c, r) in zip(layers, placed, strict=True)]


def periodic_tone_dots(layers, size, coverages, *, target=None, axes=True):
    """``tone_dots`` on a canvas that wraps around, as the torus does: a picture without a frame along its edges
    (``axes`` "x": along x only, the top and bottom edges cutting the discs that cross them).

    The radii are those the dots need with the dots across each edge as neighbours (``tone_radii_layers(...,
    periodic=True)``), and a dot whose disc crosses an edge is drawn across the opposite one too, each part cut
    by the canvas, where the picture wants ink there (``wanted_copies``). Moving edge dots inwards instead left
    the outermost pixels light and the next ones dark (a dark photo's top row 0.54 for 0.33, the next two 0.16).
    """
    pairs = [(centres, coverage) for (_, _, centres), coverage in zip(layers, coverages, strict=True)]
    colours = None if target is None else [colour for _, colour, _ in layers]
    radii = tone_radii_layers(pairs, size, colours=colours, target=target, periodic=axes)
    dots = []
    for (name, colour, centres), coverage, own in zip(layers, coverages, radii, strict=True):
        reach = float(own.max()) if len(own) else 0.0
        placed, origin = wrapped_copies(centres, size, np.array([reach, reach if axes is True else 0.0]))
        radius = own[origin]
        wanted = wanted_copies(placed, origin, coverage, size)
        home = home_indices(origin, wanted, len(centres))
        drawn = wanted & np.all((placed + radius[:, None] > 0) & (placed - radius[:, None] < size), axis=1)
        drawn[home] = False
        dots.append(Dots(name, colour, placed[home], own, copies=(placed[drawn], radius[drawn])))
    return dots


def home_positions(centres, coverage, size, reach):
    """Each dot where the picture wants its ink: where it is, or, for a dot within ``reach`` of an edge whose
    place wants less than ``UNWANTED_SHARE`` of the ink that its place across the edge wants, there (on the torus
    a dot just across the edge from a dark region belongs to it), kept on the canvas. For drawings whose dots
    stay whole (the plotter style): no lone dot on a white edge across from a black one."""
    placed, origin = wrapped_copies(centres, size, reach)
    home = placed[home_indices(origin, wanted_copies(placed, origin, coverage, size), len(centres))]
    return np.clip(home, 0.0, size)


def home_indices(origin, wanted, count):
    """Per dot, the index of the copy (``wrapped_copies``' order, the ``count`` dots first) it is drawn at: itself
    where ``wanted``, else its first copy that is."""
    home = np.arange(count)
    elsewhere = np.flatnonzero(wanted & ~wanted[origin] & (np.arange(len(origin)) >= count))
    moved, first = np.unique(origin[elsewhere], return_index=True)
    home[moved] = elsewhere[first]
    return home


def wanted_copies(placed, origin, coverage, size):
    """Which copies of the dots the picture wants: all but those where the coverage near the copy (the mean of
    the 3 x 3 pixels around its nearest pixel on the canvas) is below ``UNWANTED_SHARE`` of the most that any
    copy of the same dot has and below ``NEAR_WHITE``. Across an edge between a dark side and a white one (a
    black bar along one edge of a white page) a dot is drawn on the dark side only: its copy on the white side
    would be a sliver of ink on white, and a dot that the run left just across the edge from the dark region (on
    the torus it belongs to it) is drawn there instead of alone on white. (At half, copies were dropped along a
    photo's edges too, which came out lighter: 2:1 panorama, sigma 2 px RMSE 0.0160 against 0.0154 with every
    copy.)"""
    near = ndimage.uniform_filter(np.asarray(coverage, dtype=float), 3, mode="nearest")
    wants = near[canvas_pixels(placed, size, near.shape)]
    most = np.zeros(len(origin) and int(origin.max()) + 1)
    np.maximum.at(most, origin, wants)
    return (wants >= UNWANTED_SHARE * most[origin]) | (wants >= NEAR_WHITE)


def angular_distances(points):
    """Great-circle distance (radians) from each unit vector to its nearest other one."""
    chords = nearest_distances(points)
    return 2 * np.arcsin(np.clip(chords / 2, 0, 1))


def globe_dots(name, colour, canvas_xy, depth, angular_radii, globe_radius, centre):
    """Dots on the orthographic globe: radius ``angular_radii * globe_radius``, the axis towards the limb
    foreshortened by ``depth`` (the cosine of the angle from the view's centre), so the limb keeps its tone."""
    offset = canvas_xy - np.asarray(centre)
    return Dots(
        name,
        colour,
        canvas_xy,
        angular_radii * globe_radius,
        squash=np.clip(depth, MIN_SQUASH, 1.0),
        angle=np.arctan2(offset[:, 1], offset[:, 0]),
    )


def squash_paths(paths, dots):
    """Pen paths of round dots flattened like ``dots`` (ellipses); unchanged when the dots are round."""
    if dots.squash is None:
        return paths
    squashed = []
    for path, centre, factor, angle in zip(
        paths, dots.centres @ np.array([1.0, 1j]), dots.squash, dots.angle, strict=True
    ):
        turn = np.exp(1j * angle)
        local = (path - centre) / turn
        squashed.append(centre + (local.real * factor + 1j * local.imag) * turn)
    return squashed


def ink_radius(ink_area, count):
    """Radius at which ``count`` discs cover ``ink_area`` (the density's mass): the mean tone is kept."""
    return float(np.sqrt(ink_area / (np.pi * count)))


ORTHO_SIZE = 1000.0


def sphere_canvas(projection):
    """``(width, height)`` in user units of a sphere picture (SVG or PNG): the equirectangular map or the globe."""
    if projection == "equirect":
        return (ORTHO_SIZE * 2, ORTHO_SIZE)
    return (ORTHO_SIZE, ORTHO_SIZE)


def sphere_png_layers(projection, colours):
    """Bytes a supersampled pixel of a sphere PNG takes while it is drawn (``check_png_outputs``' ``layers``): the
    globe's outline is drawn through float coverage, in one channel where all ``colours`` (RGB) are grays; the map
    straight onto an 8-bit canvas."""
    if projection != "ortho":
        return 2
    return float_picture_layers(picture_channels(colours))


GLOBE = 0.98  # the globe's radius over half the canvas


def sphere_per_radian(projection, width=None):
    """A sphere picture's length per radian of the sphere (the map's along a meridian, the globe's at its
    centre): in user units, or, given the picture's ``width`` (any unit), in that unit."""
    canvas_width = sphere_canvas(projection)[0]
    per_radian = canvas_width / (2 * np.pi) if projection == "equirect" else GLOBE * ORTHO_SIZE / 2
    return per_radian if width is None else per_radian * width / canvas_width


def orthographic(points, view):
    """Canvas positions (``ORTHO_SIZE`` square, y down) of unit vectors seen from ``view``, and their depth
    (cosine of the angle from the view's centre; positive on the visible side)."""
    lon, lat = np.radians(view)
    centre = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(centre, east)
    half = ORTHO_SIZE / 2
    xy = np.stack([half + GLOBE * half * (points @ east), half - GLOBE * half * (points @ north)], axis=1)
    return xy, points @ centre


def equirectangular(longitude, latitude, width, centre=0.0):
    """Canvas positions of (lon, lat) degrees on a ``width × width/2`` canvas, longitude ``centre`` in the middle
    (0: lon -180 at the left)."""
    x = np.mod(np.asarray(longitude) - centre + 180, 360) / 360 * width
    return np.stack([x, (90 - latitude) / 180 * width / 2], axis=1)


# The darkness image that globe and map drawings are made tone-true against: pixels along the canvas's width.
DARKNESS_PIXELS = 720


def projected_darkness(darkness_at, projection, view):
    """The darkness of a sphere picture's canvas (``sphere_canvas``), ``(H, W)`` in [0, 1], white off the globe.

    ``darkness_at(longitude, latitude)`` (degrees, arrays) gives the sphere's darkness; each canvas pixel takes
    it at the point of the sphere that the projection draws there ("equirect": the 2:1 map centred on ``view``'s
    longitude; "ortho": the visible side around ``view``).
    """
    width, height = sphere_canvas(projection)
    columns = DARKNESS_PIXELS
    rows = int(round(columns * height / width))
    x, y = np.meshgrid((np.arange(columns) + 0.5) / columns, (np.arange(rows) + 0.5) / rows)
    if projection == "equirect":
        return np.clip(darkness_at(360.0 * x - 180.0 + view[0], 90.0 - 180.0 * y), 0.0, 1.0)
    u, v = (2 * x - 1) / GLOBE, (1 - 2 * y) / GLOBE
    inside = u * u + v * v < 1
    lon, lat = np.radians(view)
    centre = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(centre, east)
    depth = np.sqrt(np.clip(1 - u * u - v * v, 0.0, 1.0))
    points = u[inside][:, None] * east + v[inside][:, None] * north + depth[inside][:, None] * centre
    darkness = np.zeros((rows, columns))
    longitude = np.degrees(np.arctan2(points[:, 1], points[:, 0]))
    darkness[inside] = darkness_at(longitude, np.degrees(np.arcsin(np.clip(points[:, 2], -1, 1))))
    return np.clip(darkness, 0.0, 1.0)
