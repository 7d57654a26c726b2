"""What each output format holds for a point set: the bytes of CSV, SVG, PNG or GeoJSON for torus dots (one ink
or layered), sphere points and one-line drawings, from the format modules beside this one."""

import numpy as np

from ..drawing import (
    GLOBE,
    ORTHO_SIZE,
    Dots,
    angular_distances,
    capped_radii,
    equirectangular,
    flat_dots,
    globe_dots,
    ink_radius,
    inset,
    orthographic,
    projected_darkness,
    sphere_canvas,
    squash_paths,
    tone_dots,
)
from ..errors import StippleError
from ..plotter import dot_paths
from .geojson import geojson_bytes
from .png import default_png_width, png_bytes, render_line, render_picture
from .points import csv_bytes, layered_csv_bytes
from .svg import line_svg_bytes, svg_document
from .units import BLACK, WHITE, to_user_units


def line_output(points, shape, fmt, *, width=(200.0, "mm"), pen_width=None, png_width=None):
    """Bytes of a closed curve (vertices in unit coordinates, path order) in ``fmt``.

    CSV is ``x,y`` in pixel units in path order (the closing segment from the last vertex back to the first is
    implied); SVG one closed ``<path>`` of physical ``width`` stroked ``pen_width`` (physical ``(value, unit)``,
    default one input pixel); PNG the same line, ``png_width`` pixels wide (default: the input's width × 4).
    """
    rows, columns = shape
    pixels = np.asarray(points) * np.array([columns, rows])
    if fmt == ".csv":
        return csv_bytes([pixels[:, 0], pixels[:, 1]], ["x", "y"])
    if fmt in (".geojson", ".json"):
        raise StippleError("GeoJSON output is for sphere points")
    stroke = 1.0 if pen_width is None else to_user_units(pen_width, width, columns)
    if fmt == ".svg":
        return line_svg_bytes(
            pixels, (columns, rows), width, stroke, comment=f"one closed line, {len(pixels)} vertices"
        )
    return png_bytes(render_line(pixels, (columns, rows), png_width or 4 * columns, stroke))


def with_pen_paths(layers, dot_style, pen):
    """The layers with pen paths (``stipple.plotter.dot_paths``) for a pen style; unchanged for "disc"."""
    if dot_style == "disc":
        return layers
    for dots in layers:
        dots.paths = squash_paths(dot_paths(dots.centres, dots.radii, dot_style, pen), dots)
    return layers


def _look(width, columns, dot_radius, dot_style, pen_width):
    """The fixed radius (user units, or None for the default) and the pen width in user units."""
    radius = None if dot_radius is None else to_user_units(dot_radius, width, columns)
    pen = to_user_units(pen_width, width, columns)
    return radius, (pen if dot_style != "disc" else None), pen


def draw_layers(layers, fmt, size, *, width, png_width, count, pen, background=WHITE, blend="over", notes=()):
    """SVG or PNG bytes of ``Dots`` layers."""
    if fmt == ".svg":
        return svg_document(layers, size, width, background=background, pen_width=pen, notes=notes)
    picture = render_picture(
        layers, size, png_width or default_png_width(count), background=background, pen_width=pen, blend=blend
    )
    return png_bytes(picture)


def torus_output(points, shape, fmt, *, darkness=None, **options):
    """Bytes of torus ``points`` (unit coordinates) in ``fmt`` for an image of ``shape = (H, W)``: one layer
    of dots in ``color`` on ``background`` (see ``layered_torus_output``; CSV is ``x,y`` in pixels).

    ``darkness`` is the density ``w`` (H, W) the dots were placed from: the ink the tone style reproduces."""
    if fmt == ".csv":
        rows, columns = shape
        pixels = points * np.array([columns, rows])
        return csv_bytes([pixels[:, 0], pixels[:, 1]], ["x", "y"])
    color = options.pop("color", BLACK)
    if darkness is not None:
        options.setdefault("ink", float(np.mean(darkness)))
        options["coverages"] = [darkness]
    return layered_torus_output([("dots", color, points)], shape, fmt, blend="over", **options)


def layered_torus_output(
    layers,
    shape,
    fmt,
    *,
    width=(200.0, "mm"),
    dot_radius=None,
    png_width=None,
    ink=None,
    dot_style="disc",
    pen_width=(0.3, "mm"),
    background=WHITE,
    blend="multiply",
    style="tone",
    coverages=None,
    target=None,
    notes=(),
):
    """Bytes of layered torus dots in ``fmt``; ``layers`` are ``(name, colour, points)`` with points in unit
    coordinates of an image of ``shape = (H, W)``.

    CSV is ``x,y,layer`` in pixels; SVG one Inkscape layer per ink; PNG the inks printed on ``background``.
    ``style`` "tone" (given ``coverages``, each ink's target coverage (H, W), and filled discs): each dot's
    radius makes the drawn ink reproduce its coverage, darks included (``stipple.drawing.tone_dots``; with
    ``target``, the (H, W, 3) colour the inks multiplied on white must print); dots crossing the edge move in.
    "plotter": the radius that makes the dots' ink equal ``ink`` (the density's mean; 0.5 if unknown), capped
    at 0.45 × the distance to the nearest dot of any layer, so no two dots touch, and the drawing inset by the
    largest radius (``stipple.drawing.flat_dots``). The CSV keeps the exact positions. ``dot_radius``
    (physical ``(value, unit)``) fixes every radius. ``dot_style`` "disc" draws filled discs; "circle",
    "filled" and "point" pen paths ``pen_width`` wide (a plotter preview in the PNG). ``notes`` are added to
    the SVG's comments and description.
    """
    extra_notes = list(notes)
    rows, columns = shape
    count = sum(len(points) for _, _, points in layers)
    placed = [(name, colour, points * np.array([columns, rows])) for name, colour, points in layers]
    if fmt == ".csv":
        pixels = np.concatenate([centres for _, _, centres in placed])
        names = [name for name, _, centres in placed for _ in range(len(centres))]
        return layered_csv_bytes(pixels, names)
    if fmt in (".geojson", ".json"):
        raise StippleError("GeoJSON output is for sphere points")
    radius, stroke, pen = _look(width, columns, dot_radius, dot_style, pen_width)
    if style == "tone" and coverages is not None and radius is None and dot_style == "disc":
        drawn = tone_dots(placed, (columns, rows), coverages, target=target)
        notes = [f"{count} dots in {len(drawn)} layer(s), tone-true radii"]
    else:
        tone = ink_radius((0.5 if ink is None else ink) * rows * columns, max(count, 1))
        drawn = flat_dots(placed, (columns, rows), tone_radius=tone, radius=radius, pen=stroke)
        drawn = with_pen_paths(drawn, dot_style, pen)
        margin = _margin(drawn, stroke)
        notes = [f"{count} dots in {len(drawn)} layer(s), inset {margin:.4g} user units from the edges"]
    notes = [*notes, *extra_notes]
    return draw_layers(
        drawn,
        fmt,
        (columns, rows),
        width=width,
        png_width=png_width,
        count=count,
        pen=pen,
        background=background,
        blend=blend,
        notes=notes,
    )


def _margin(layers, pen):
    """The largest radius drawn (or half the pen), for the SVG's note."""
    radii = [dots.radii.max() for dots in layers if len(dots.radii)]
    return max(radii + [(pen or 0.0) / 2])


def sphere_output(
    points,
    lon_lat,
    fmt,
    *,
    coords="lonlat",
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
    """Bytes of sphere ``points`` (unit vectors; ``lon_lat`` their degrees) in ``fmt``.

    CSV is ``lon,lat`` in degrees or ``x,y,z``; GeoJSON a MultiPoint. SVG and PNG draw ``projection``:
    "equirect" every dot on the 2:1 map (inset from the edges like torus dots), "ortho" the visible side of
    the globe around ``view = (lon, lat)``, each dot foreshortened towards the limb (an ellipse), so the limb
    keeps its tone; the SVG says how many dots are on the visible side. ``style`` "plotter" (or "tone" without
    ``darkness_at``, e.g. a uniform sphere): the angular radius that keeps the mean tone (``ink``, 0.5 if
    unknown), capped at 0.45 × the great-circle distance to the nearest dot. "tone" with ``darkness_at(lon,
    lat)`` (the map's darkness in [0, 1]): round dots sized on the drawn canvas so that the picture has the
    map's tone, darks included (``stipple.drawing.tone_dots`` against ``projected_darkness``).
    """
    longitude, latitude = lon_lat
    if fmt == ".csv":
        if coords == "xyz":
            return csv_bytes(list(points.T), ["x", "y", "z"], number_format=".17g")
        # Round-trip digits: 6 decimals of a degree would cap a spherical design's error near 6e-8.
        return csv_bytes([longitude, latitude], ["lon", "lat"], number_format=".17g")
    if fmt in (".geojson", ".json"):
        return geojson_bytes(np.stack([longitude, latitude], axis=1), {"points": len(points)})
    canvas = sphere_canvas(projection)
    fixed, stroke, pen = _look(width, canvas[0], dot_radius, dot_style, pen_width)
    if style == "tone" and darkness_at is not None and fixed is None and dot_style == "disc":
        drawn, notes = _tone_sphere(points, lon_lat, projection, view, color, darkness_at)
        return _sphere_picture([drawn], fmt, canvas, projection, width, png_width, background, pen, notes)
    per_radian = canvas[0] / (2 * np.pi) if projection == "equirect" else GLOBE * ORTHO_SIZE / 2
    tone = 2 * np.sqrt((0.5 if ink is None else ink) / max(len(points), 1))
    angles = (
        capped_radii(angular_distances(points), tone) if fixed is None else np.full(len(points), fixed / per_radian)
    )
    if projection == "equirect":
        centres, margin = inset(
            equirectangular(longitude, latitude, canvas[0]), canvas, per_radian * angles.max(initial=0)
        )
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
    layers = with_pen_paths([drawn], dot_style, pen)
    return _sphere_picture(layers, fmt, canvas, projection, width, png_width, background, pen, notes)


def _tone_sphere(points, lon_lat, projection, view, color, darkness_at):
    """One layer of tone-true round dots on the sphere picture's canvas, and the SVG's note."""
    canvas = sphere_canvas(projection)
    if projection == "equirect":
        centres = equirectangular(*lon_lat, canvas[0])
        note = f"{len(points)} dots, equirectangular (all of them), tone-true radii"
    else:
        centres, depth = orthographic(points, view)
        centres = centres[depth > 0]
        note = (
            f"{len(centres)} of {len(points)} dots on the visible side (orthographic, view "
            f"{view[0]:g},{view[1]:g}), tone-true radii"
        )
    coverage = projected_darkness(darkness_at, projection, view)
    return tone_dots([("dots", color, centres)], canvas, [coverage])[0], [note]


def _sphere_picture(layers, fmt, canvas, projection, width, png_width, background, pen, notes):
    """SVG or PNG bytes of a sphere picture's layers (the globe's outline under an orthographic PNG)."""
    if fmt == ".svg":
        return svg_document(layers, canvas, width, background=background, pen_width=pen, notes=notes)
    count = sum(len(dots.centres) for dots in layers)
    picture = render_picture(
        layers,
        canvas,
        png_width or default_png_width(count),
        background=background,
        pen_width=pen,
        underlay=_globe_outline if projection == "ortho" else None,
    )
    return png_bytes(picture)


def _globe_outline(draw, scale):
    """The globe's disc, marking its outline on the PNG."""
    low, high = (1 - GLOBE) / 2 * ORTHO_SIZE * scale, (1 + GLOBE) / 2 * ORTHO_SIZE * scale
    draw.ellipse((low, low, high, high), fill=255)
