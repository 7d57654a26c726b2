"""The drawing: points made into a finished ``Drawing`` (positions, radii, colours, layers, pen paths, canvas),
every choice made here once, so that a writer (``stipple.io.writers``) only serialises it.

Modules: ``drawing`` (the ``Drawing`` record), ``flat`` (drawings on an image's canvas: torus dots of one ink or
of several, one closed line), ``globe`` (sphere points on the orthographic globe or the equirectangular map),
``dots`` (the geometry of drawn dots: radii that keep the tone without letting neighbours touch, insets,
foreshortened dots on the globe), ``pen`` (pen plotters: a short pen-up order and the pen paths that draw a dot),
``pen_count`` (``-M auto``: the dot count from the pen and the paper),
``styles`` (the named choices, without numpy, for ``--help``). Tone-true radii are ``stipple.tone``'s. The
public names load on first use (``stipple.lazy``).
"""

from ..lazy import lazy_names
from .styles import DOT_STYLES, PROJECTIONS, STYLES

_WHERE = {
    "Drawing": ".drawing",
    "Dots": ".dots",
    "torus_drawing": ".flat",
    "layered_drawing": ".flat",
    "line_drawing": ".flat",
    "sphere_drawing": ".globe",
    "pen_order": ".pen",
    "dot_paths": ".pen",
}
__all__ = ["DOT_STYLES", "PROJECTIONS", "STYLES", *sorted(_WHERE)]
__getattr__ = lazy_names(__name__, _WHERE)
