"""The drawing: points made into a finished ``Drawing`` (positions, radii, colours, layers, pen paths, canvas),
every choice made here once, so that a writer (``stipple.io``) only serialises it.

Modules: ``styles`` (the named choices, without numpy), ``dots`` (the geometry of drawn dots: radii that keep
the tone without letting neighbours touch, insets, foreshortened dots on the globe), ``pen`` (pen plotters: a
short pen-up path and the pen paths that draw a dot). Tone-true radii are ``stipple.tone``'s.
"""

from .styles import DOT_STYLES, PROJECTIONS, STYLES

__all__ = ["DOT_STYLES", "PROJECTIONS", "STYLES"]
