"""``Drawing``: a finished picture, every choice made, that ``stipple.io.writers`` serialises as SVG or PNG."""

from dataclasses import dataclass, field

from ..io.units import BLACK, WHITE


@dataclass
class Drawing:
    """A picture on a canvas of ``size = (width, height)`` user units, ``width = (value, unit)`` wide on paper and
    ``png_width`` pixels wide as a PNG.

    Either ``layers`` of dots (``stipple.render.dots.Dots``: centres, radii, colours, foreshortening, pen paths),
    laid on ``background`` one over the other (``blend`` "over") or printed as inks ("multiply"), pen paths
    stroked ``pen_width`` user units wide; or one closed ``line`` (vertices in user units) stroked ``stroke``
    wide in ``line_colour`` on ``background``. ``notes`` describe it (SVG comments), ``warnings`` are the notes a
    user must also see (dots left out); ``outline``, a box ``(left, top, right, bottom)``, is the globe's disc,
    shaded under the first layer in the PNG. ``layer_numbers`` number the SVG's layers (default 1, 2, ...): an
    ink's place in its palette, so that a pen keeps its slot where an ink got no dots.
    """

    size: tuple
    width: tuple
    png_width: int
    layers: list = field(default_factory=list)
    background: tuple = WHITE
    pen_width: float | None = None
    blend: str = "over"
    notes: tuple = ()
    warnings: tuple = ()
    outline: tuple | None = None
    line: object = None
    stroke: float = 1.0
    line_colour: tuple = BLACK
    layer_numbers: tuple | None = None

    @property
    def count(self):
        """The number of dots drawn (or of the line's vertices)."""
        return len(self.line) if self.line is not None else sum(len(dots.centres) for dots in self.layers)
