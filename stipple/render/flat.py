"""Drawings on an image's flat canvas (user units: the image's pixels): torus dots of one ink or of several
layered inks, and one closed line."""

import numpy as np

from ..io.png import default_png_width, render_line
from ..io.units import BLACK, WHITE, to_user_units
from .dots import (
    capped_margin,
    check_pen_fits,
    flat_dots,
    home_positions,
    ink_radius,
    left_out_note,
    pen_extent,
    squash_paths,
    tone_dots,
)
from .drawing import Drawing
from .pen import closed_length, dot_paths


def torus_drawing(points, shape, *, darkness=None, color=BLACK, **options):
    """The ``Drawing`` of torus ``points`` (unit coordinates) for an image of ``shape = (H, W)``: one layer of dots
    in ``color`` (see ``layered_drawing``). ``darkness`` is the density ``w`` (H, W) the dots were placed from:
    the ink the tone style reproduces."""
    if darkness is not None:
        options.setdefault("ink", float(np.mean(darkness)))
        options["coverages"] = [darkness]
    return layered_drawing([("dots", color, points)], shape, blend="over", **options)


def layered_drawing(
    layers,
    shape,
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
    """The ``Drawing`` of layered torus dots; ``layers`` are ``(name, colour, points)`` with points in unit
    coordinates of an image of ``shape = (H, W)``, one Inkscape layer (one pen) per ink in the SVG.

    ``style`` "tone" (given ``coverages``, each ink's target coverage (H, W), and filled discs): each dot's
    radius makes the drawn ink reproduce its coverage, darks included (``stipple.render.dots.tone_dots``; with
    ``target``, the (H, W, 3) colour the inks multiplied on white must print); the canvas wraps around as the torus
    does, a dot crossing an edge drawn across the opposite one too (``periodic_tone_dots``).
    "plotter": the radius that makes the dots' ink equal ``ink`` (the density's mean; 0.5 if unknown), capped
    at 0.45 × the distance to the nearest dot of any layer, so no two dots touch, and the drawing inset by the
    largest radius (``stipple.render.dots.flat_dots``). ``dot_radius`` (physical ``(value, unit)``) fixes every
    radius. ``dot_style`` "disc" draws filled discs; "circle", "filled" and "point" pen paths ``pen_width`` wide
    (a plotter preview in the PNG). ``notes`` (lines of text, e.g. why ``-M auto`` chose M) are added to the
    drawing's own notes (the SVG's comments and description).
    """
    extra_notes, warnings = list(notes), []
    rows, columns = shape
    count = sum(len(points) for _, _, points in layers)
    placed = [(name, colour, points * np.array([columns, rows])) for name, colour, points in layers]
    radius, stroke, pen = drawn_sizes(width, columns, dot_radius, dot_style, pen_width)
    if style == "tone" and coverages is not None and radius is None and dot_style == "disc":
        drawn = tone_dots(placed, (columns, rows), coverages, target=target, periodic=True)
        copies = sum(len(dots.copies[0]) for dots in drawn if dots.copies is not None)
        across = f", and {copies} copies of those crossing an edge drawn across the opposite one" if copies else ""
        notes = [f"{count} dots in {len(drawn)} layer(s), tone-true radii{across}"]
    else:
        tone = ink_radius((0.5 if ink is None else ink) * rows * columns, max(count, 1))
        if coverages is not None:
            reach = 2 * (tone if radius is None else radius)
            placed = [
                (name, colour, home_positions(centres, coverage, (columns, rows), reach))
                for (name, colour, centres), coverage in zip(placed, coverages, strict=True)
            ]
        drawn = flat_dots(placed, (columns, rows), tone_radius=tone, radius=radius, pen=stroke, dot_style=dot_style)
        drawn = with_pen_paths(drawn, dot_style, pen)
        margin = _margin(drawn, None if stroke is None else pen_extent(dot_style, stroke))
        notes = [f"{count} dots in {len(drawn)} layer(s), inset {margin:.4g} user units from the edges"]
        left_out = count - sum(len(dots.centres) for dots in drawn)
        if left_out:
            warnings.append(left_out_note(left_out, f"{count} dots", " (the darkest tones)"))
    return Drawing(
        (columns, rows),
        width,
        png_width or default_png_width(count, (columns, rows)),
        drawn,
        background=background,
        pen_width=pen,
        blend=blend,
        notes=(*notes, *warnings, *extra_notes),
        warnings=tuple(warnings),
    )


# Corrections of the tone stroke by the ink of the line drawn with it (``tone_stroke``), measured on a picture
# twice the image's width, at most STROKE_PICTURE_WIDTH pixels (drawn at 4 x that: the memory stays bounded).
STROKE_PASSES = 3
STROKE_PICTURE_WIDTH = 2048
# A line's PNG is this many pixels wide per input pixel unless --png-width says otherwise.
LINE_PNG_SCALE = 4


def line_png_width(png_width, shape):
    """A line drawing's PNG width: ``png_width``, or ``LINE_PNG_SCALE`` times the input's ``(rows, columns)``
    width."""
    return png_width or LINE_PNG_SCALE * shape[1]


def line_drawing(
    points, shape, *, width=(200.0, "mm"), pen_width=None, png_width=None, color=BLACK, background=WHITE, ink=None
):
    """The ``Drawing`` of a closed curve (vertices in unit coordinates, path order) for an image of ``shape``: one
    closed path of physical ``width`` stroked ``pen_width`` (physical ``(value, unit)``) in ``color`` on
    ``background`` (``--invert``: white on black), ``png_width`` pixels wide as a PNG (default:
    ``line_png_width``). Without ``pen_width`` the stroke is ``tone_stroke`` for ``ink``, the density's mean (one
    input pixel without it). Vertices closer to an edge than half the stroke are drawn that far from it
    (``within``), so that no stroke inks past the page: the run's vertices rest on the image's edges, and a
    plotter drew up to half a stroke beyond them."""
    rows, columns = shape
    size = (columns, rows)
    pixels = np.asarray(points) * np.array([columns, rows])
    if pen_width is not None:
        stroke = to_user_units(pen_width, width, columns)
        margin = stroke / 2  # a given pen too wide for the page is refused (``within``)
    elif ink is None:
        stroke, margin = 1.0, capped_margin(0.5, size)
    else:
        # The tone stroke of the line as drawn, kept half the stroke first found for it from the edges (at most
        # MAX_MARGIN of the shorter side: a dark strip a few pixels high asks for a stroke wider than that).
        first = tone_stroke(pixels, shape, ink)
        stroke = tone_stroke(within(pixels, size, capped_margin(first / 2, size)), shape, ink)
        margin = capped_margin(max(first, stroke) / 2, size)
    return Drawing(
        size,
        width,
        line_png_width(png_width, shape),
        notes=(f"one closed line, {len(pixels)} vertices, stroke {stroke:.3g} px",),
        background=tuple(background),
        line=within(pixels, size, margin),
        stroke=stroke,
        line_colour=tuple(color),
    )


def within(pixels, size, margin):
    """``pixels`` moved to at least ``margin`` from the edges of a ``size = (width, height)`` canvas (a pen too
    wide for the page refused, as for dots: ``check_pen_fits``): an affine inset as the dots' (``inset``) moved a
    ramp's whole top row of strokes off it, 0.40 of ink drawn 0.10."""
    extent = np.asarray(size, dtype=np.float64)
    check_pen_fits(margin, extent, "its strokes ink")
    return np.clip(pixels, margin, extent - margin)


def tone_stroke(pixels, shape, ink, passes=STROKE_PASSES):
    """The stroke width (pixels) whose ink along the closed line through ``pixels`` covers ``ink`` of the image:
    ``ink W H / length`` to start with, then scaled ``passes`` times by ``ink`` over the ink the line drawn with it
    lays down (``render_line`` at twice the image's width, at most ``STROKE_PICTURE_WIDTH``), which is less where
    the stroke crosses or touches itself. The line's length per area follows the density, so the drawn tone
    follows it too, to where strokes touch (at density 1). A 1-pixel stroke drew the 3:1 panorama of the held-out
    sweep at mean 0.29 too light (darkest tenth 0.51 for 0.06); the first estimate alone drew a 2:1 photo 0.017
    too light, a dark one 0.031."""
    rows, columns = shape
    length = closed_length(pixels)
    if not length > 0:
        return 1.0
    stroke = float(ink) * rows * columns / length
    for _ in range(passes):
        picture = render_line(pixels, (columns, rows), min(2 * columns, STROKE_PICTURE_WIDTH), stroke)
        drawn = 1.0 - np.asarray(picture, dtype=np.float64) / 255
        if not drawn.mean() > 0:
            break
        stroke *= float(ink) / drawn.mean()
    return stroke


def with_pen_paths(layers, dot_style, pen):
    """The layers with pen paths (``stipple.render.pen.dot_paths``) for a pen style; unchanged for "disc"."""
    if dot_style == "disc":
        return layers
    for dots in layers:
        dots.paths = squash_paths(dot_paths(dots.centres, dots.radii, dot_style, pen), dots)
    return layers


def drawn_sizes(width, columns, dot_radius, dot_style, pen_width):
    """The fixed radius (user units, or None for the default), the pen width of pen-drawn dots (None for
    discs) and the pen width, in user units."""
    radius = None if dot_radius is None else to_user_units(dot_radius, width, columns)
    pen = to_user_units(pen_width, width, columns)
    return radius, (pen if dot_style != "disc" else None), pen


def _margin(layers, least):
    """The largest radius drawn (or the smallest pen dot's ink, ``least``), for the SVG's note."""
    radii = [dots.radii.max() for dots in layers if len(dots.radii)]
    return max(radii + [least or 0.0])
