"""Drawings of sphere points: the orthographic globe or the equirectangular map."""

import numpy as np

from ..errors import StippleError
from ..io.png import default_png_width
from ..io.units import BLACK, WHITE
from .dots import (
    GLOBE,
    ORTHO_SIZE,
    TOUCH_FRACTION,
    Dots,
    angular_distances,
    capped_radii,
    equirectangular,
    globe_dots,
    inset,
    least_pen_reach,
    left_out_note,
    nearest_distances,
    orthographic,
    pen_extent,
    projected_darkness,
    sphere_canvas,
    sphere_per_radian,
    thin_dots,
    tone_dots,
)
from .drawing import Drawing
from .flat import drawn_sizes, with_pen_paths

# A pen drawing's globe is made smaller so that its limb dots stay on the canvas (``globe_fit``), but not below
# this share of its size: a pen that needs more is refused.
MIN_GLOBE_FIT = 0.5


def sphere_drawing(
    points,
    lon_lat,
    *,
    projection="ortho",
    view=(0.0, 0.0),
    width=(200.0, "mm"),
    dot_radius=None,
    png_width=None,
    ink=None,
    color=BLACK,
    background=WHITE,
    dot_style="disc",
    pen_width=(0.3, "mm"),
    style="tone",
    darkness_at=None,
):
    """The ``Drawing`` of sphere ``points`` (unit vectors; ``lon_lat`` their degrees).

    ``projection`` "equirect" draws every dot on the 2:1 map centred on ``view``'s longitude (inset from the edges
    like torus dots), "ortho" the
    visible side of the globe around ``view = (lon, lat)``, each dot foreshortened towards the limb (an
    ellipse), so the limb keeps its tone; the notes say how many dots are on the visible side. ``style``
    "plotter" (or "tone" without ``darkness_at``, e.g. a uniform sphere): the angular radius that keeps the mean
    tone (``ink``, 0.5 if unknown), capped at 0.45 × the great-circle distance to the nearest dot. "tone" with
    ``darkness_at(lon, lat)`` (the map's darkness in [0, 1]): round dots sized on the drawn canvas so that the
    picture has the map's tone, darks included (``stipple.render.dots.tone_dots`` against
    ``projected_darkness``).
    """
    longitude, latitude = lon_lat
    canvas = sphere_canvas(projection)
    fixed, stroke, pen = drawn_sizes(width, canvas[0], dot_radius, dot_style, pen_width)
    if style == "tone" and darkness_at is not None and fixed is None and dot_style == "disc":
        drawn, notes = _tone_sphere(points, lon_lat, projection, view, color, darkness_at)
        return _sphere_picture([drawn], canvas, projection, width, png_width, background, pen, notes)
    per_radian = sphere_per_radian(projection)
    tone = 2 * np.sqrt((0.5 if ink is None else ink) / max(len(points), 1))
    warnings = []
    angles = (
        capped_radii(angular_distances(points), tone) if fixed is None else np.full(len(points), fixed / per_radian)
    )
    least = 0.0 if stroke is None else pen_extent(dot_style, stroke)
    if projection == "equirect":
        largest = max(per_radian * angles.max(initial=0), least)
        centres, margin = inset(equirectangular(longitude, latitude, canvas[0], view[0]), canvas, largest, least)
        drawn = Dots("dots", color, centres, np.minimum(angles * per_radian, margin))
        notes = [f"{len(points)} dots, equirectangular (all of them)"]
    else:
        centres, depth = orthographic(points, view)
        visible = depth > 0
        half = ORTHO_SIZE / 2
        drawn = globe_dots("dots", color, centres[visible], depth[visible], angles[visible], per_radian, (half, half))
        notes = [
            f"{int(visible.sum())} of {len(points)} dots on the visible side (orthographic, view "
            f"{view[0]:g},{view[1]:g}; dots foreshortened towards the limb)"
        ]
    globe = GLOBE
    if projection == "ortho" and stroke is not None:
        shrink = globe_fit(drawn, least)
        drawn.centres = ORTHO_SIZE / 2 + (drawn.centres - ORTHO_SIZE / 2) * shrink
        globe *= shrink
    if stroke is not None and fixed is None:
        # Foreshortening brings dots near the limb closer (and the map's inset those at its edges), but not the
        # pen's width: the pen's dots are kept apart on the drawing itself (thinned, and each dot's radius capped
        # by its drawn nearest distance).
        shown = len(drawn.centres)  # the globe's visible side, the map's every dot
        drawn, left_out = thin_dots(drawn, least_pen_reach(dot_style, stroke) / TOUCH_FRACTION)
        drawn.radii = np.minimum(drawn.radii, TOUCH_FRACTION * nearest_distances(drawn.centres))
        if left_out:
            warnings = [left_out_note(left_out, f"the {shown} dots shown")]
    layers = with_pen_paths([drawn], dot_style, pen)
    return _sphere_picture(layers, canvas, projection, width, png_width, background, pen, notes, warnings, globe)


def globe_fit(dots, least):
    """The factor (at most 1) by which the orthographic globe's dots must come towards its centre, their radii
    kept, so that every dot's ink (its radius towards the limb, at least ``least``: ``pen_extent``) stays on the
    canvas. Near the limb the dots are foreshortened but the pen is not: a 5 mm pen on a 100 mm globe inked
    1.4 mm past the edge. The pen's dots are thinned after it, on the drawing as it will be."""
    half = ORTHO_SIZE / 2
    distance = np.hypot(*(dots.centres - half).T)
    reach = np.maximum(dots.radii * dots.squash, least)
    outer = distance > 0
    shrink = min(1.0, float(np.min((half - reach[outer]) / distance[outer], initial=1.0)))
    if shrink < MIN_GLOBE_FIT:
        raise StippleError(
            f"the pen is too wide for the globe: its dots ink {np.max(reach) / half:.0%} of the globe's radius from "
            "their centres; give a narrower --pen-width or a larger --width"
        )
    return shrink


def _tone_sphere(points, lon_lat, projection, view, color, darkness_at):
    """One layer of tone-true round dots on the sphere picture's canvas, and the notes."""
    canvas = sphere_canvas(projection)
    if projection == "equirect":
        centres = equirectangular(*lon_lat, canvas[0], view[0])
        note = f"{len(points)} dots, equirectangular (all of them), tone-true radii"
    else:
        centres, depth = orthographic(points, view)
        centres = centres[depth > 0]
        note = (
            f"{len(centres)} of {len(points)} dots on the visible side (orthographic, view "
            f"{view[0]:g},{view[1]:g}), tone-true radii"
        )
    coverage = projected_darkness(darkness_at, projection, view)
    # Longitude wraps: the map's left and right edges are one meridian (drawn as a frame, they showed a light line
    # and a dark band at 1:1: a held-out review); its top and bottom are the poles.
    periodic = "x" if projection == "equirect" else False
    return tone_dots([("dots", color, centres)], canvas, [coverage], periodic=periodic)[0], [note]


def _sphere_picture(layers, canvas, projection, width, png_width, background, pen, notes, warnings=(), globe=GLOBE):
    """The ``Drawing`` of a sphere picture's layers (the globe's outline, ``globe`` of the canvas, under an
    orthographic PNG)."""
    count = sum(len(dots.centres) for dots in layers)
    low, high = (1 - globe) / 2 * ORTHO_SIZE, (1 + globe) / 2 * ORTHO_SIZE
    return Drawing(
        canvas,
        width,
        png_width or default_png_width(count, canvas),
        layers,
        background=background,
        pen_width=pen,
        notes=(*notes, *warnings),
        warnings=tuple(warnings),
        outline=(low, low, high, high) if projection == "ortho" else None,
    )
