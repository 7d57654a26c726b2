"""SVG documents: dots as circles, ellipses or pen paths, one Inkscape layer per ink; one-line drawings as a path."""

import numpy as np

from .units import BLACK, WHITE, hex_colour


def line_svg_bytes(pixels, size, physical_width, pen_width, comment="", colour=BLACK, background=WHITE):
    """One closed ``<path>`` (``M x y L ... Z``) stroked ``pen_width`` user units wide in ``colour``, unfilled, on
    ``background`` (a filled rectangle unless white).

    The path sits in one Inkscape layer named "line" whose group carries the stroke, so ``vpype read`` and
    plotter software see one pen of that width; the page is ``physical_width`` wide (user units: input pixels).
    """
    width, height = size
    value, unit = physical_width
    points = " ".join(f"{x:.3f},{y:.3f}" for x, y in pixels)
    return "\n".join(
        [
            '<?xml version="1.0" encoding="UTF-8"?>',
            '<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
            f'width="{value:g}{unit}" height="{value * height / width:.6g}{unit}" viewBox="0 0 {width:g} {height:g}">',
            f"<!-- {comment} -->" if comment else "",
            *_background(background, size),
            f'<g id="layer1" inkscape:groupmode="layer" inkscape:label="1-line" fill="none" '
            f'stroke="{hex_colour(colour)}" '
            f'stroke-width="{pen_width:.4f}" stroke-linecap="round" stroke-linejoin="round">',
            f'<path d="M {points} Z"/>',
            "</g>",
            "</svg>\n",
        ]
    ).encode()


def path_data(path):
    """SVG path data of a polyline given as complex vertices."""
    return "M" + " L".join(f"{z.real:.4f},{z.imag:.4f}" for z in path)


def svg_document(
    layers, size, physical_width, *, background=WHITE, pen_width=None, notes=(), blend="over", numbers=None
):
    """SVG of ``Dots`` layers, one Inkscape layer each, on a ``size = (width, height)`` user-unit canvas.

    Round dots are circles, foreshortened ones ellipses, pen-drawn ones stroked paths ``pen_width`` wide.
    Filled dots also carry a stroke of their colour (width 0), so that ``vpype read`` keeps each layer's pen
    colour. ``notes`` become comments and the ``<desc>``; a background other than white is a filled rectangle.
    ``blend`` "multiply" (inks printed over each other, as the PNG draws them) gives every layer the CSS
    ``mix-blend-mode: multiply`` (browsers, Inkscape); "over" paints each layer over the ones before. ``numbers``
    are the layers' numbers (ids ``layer<n>``, labels ``<n>-<name>``; default 1, 2, ...).
    """
    width, height = size
    value, unit = physical_width
    parts = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        f'width="{value:g}{unit}" height="{value * height / width:.6g}{unit}" viewBox="0 0 {width:g} {height:g}">',
    ]
    parts.extend(f"<!-- {note} -->" for note in notes)
    if notes:
        parts.append(f"<desc>{'; '.join(notes)}</desc>")
    parts.extend(_background(background, size))
    for index, dots in zip(numbers or range(1, len(layers) + 1), layers, strict=True):
        parts.append(_svg_layer(index, dots, pen_width, blend))
    parts.append("</svg>\n")
    return "\n".join(parts).encode()


def _circles(centres, radii, attributes=""):
    return [
        f'<circle cx="{x:.4f}" cy="{y:.4f}" r="{r:.4f}"{attributes}/>' for (x, y), r in zip(centres, radii, strict=True)
    ]


def _background(background, size):
    """A filled rectangle under the drawing (as a list of one line), or none on white paper."""
    if tuple(background) == WHITE:
        return []
    width, height = size
    return [f'<rect x="0" y="0" width="{width:g}" height="{height:g}" fill="{hex_colour(background)}"/>']


def _svg_layer(index, dots, pen_width, blend="over"):
    colour = hex_colour(dots.colour)
    label = f'id="layer{index}" inkscape:groupmode="layer" inkscape:label="{index}-{dots.name}"'
    if blend == "multiply":
        label += ' style="mix-blend-mode:multiply"'
    if dots.paths is not None:
        head = (
            f'<g {label} fill="none" stroke="{colour}" stroke-width="{pen_width:.4f}" '
            'stroke-linecap="round" stroke-linejoin="round">'
        )
        body = [f'<path d="{path_data(path)}"/>' for path in dots.paths]
    elif dots.squash is None:
        head = f'<g {label} fill="{colour}" stroke="{colour}" stroke-width="0">'
        body = _circles(dots.centres, dots.radii)
        if dots.copies is not None:
            # A wrapping page's discs across its edges, as the PNG draws them (marked: they are not dots of their own).
            body += _circles(*dots.copies, ' class="copy"')
    else:
        head = f'<g {label} fill="{colour}" stroke="{colour}" stroke-width="0">'
        body = [
            f'<ellipse cx="{x:.4f}" cy="{y:.4f}" rx="{r * s:.4f}" ry="{r:.4f}" '
            f'transform="rotate({np.degrees(a):.2f} {x:.4f} {y:.4f})"/>'
            for (x, y), r, s, a in zip(dots.centres, dots.radii, dots.squash, dots.angle, strict=True)
        ]
    return "\n".join([head, *body, "</g>"])
