"""Writers of finished drawings: the SVG or PNG bytes of a ``stipple.render.drawing.Drawing``, decided nothing
(every radius, colour, layer and pen path is the drawing's)."""

from .png import SUPERSAMPLE, png_bytes, render_line, render_picture
from .svg import line_svg_bytes, svg_document


def drawing_bytes(drawing, fmt):
    """The bytes of ``drawing`` as ``fmt`` (".svg" or ".png")."""
    if drawing.line is not None:
        return _line_bytes(drawing, fmt)
    if fmt == ".svg":
        return svg_document(
            drawing.layers,
            drawing.size,
            drawing.width,
            background=drawing.background,
            pen_width=drawing.pen_width,
            notes=drawing.notes,
            blend=drawing.blend,
            numbers=drawing.layer_numbers,
        )
    picture = render_picture(
        drawing.layers,
        drawing.size,
        drawing.png_width,
        background=drawing.background,
        pen_width=drawing.pen_width,
        blend=drawing.blend,
        underlay=None if drawing.outline is None else _outline(drawing.outline),
    )
    return png_bytes(picture)


def _line_bytes(drawing, fmt):
    """SVG or PNG bytes of a drawing of one closed line."""
    colours = {"colour": drawing.line_colour, "background": drawing.background}
    if fmt == ".svg":
        comment = drawing.notes[0] if drawing.notes else ""
        return line_svg_bytes(drawing.line, drawing.size, drawing.width, drawing.stroke, comment=comment, **colours)
    return png_bytes(render_line(drawing.line, drawing.size, drawing.png_width, drawing.stroke, **colours))


def _outline(box):
    """The underlay that marks the globe's edge, the circle in ``box`` (user units), on the PNG's coverage mask: a
    ring one output pixel wide. (A filled disc painted the whole globe 8 % gray, so a map's white parts came out
    0.08 dark and the blurred tone 0.06 darker than the map's where it was light.)"""

    def draw(canvas, scale):
        sx, sy = scale
        canvas.ellipse((box[0] * sx, box[1] * sy, box[2] * sx, box[3] * sy), outline=255, width=SUPERSAMPLE)

    return draw
