"""The drawing's named choices (no numpy: the command line shows them in ``--help``)."""

# How dots are sized: "tone" (tone-true radii, ``stipple.tone``) or "plotter" (one radius, capped so no two touch).
STYLES = ("tone", "plotter")
# Pen paths a plotter draws for a dot (``stipple.render.pen.dot_paths``); "disc" is a filled disc, no path.
DOT_STYLES = ("circle", "filled", "point")
# Pictures of sphere points: the orthographic globe or the equirectangular map.
PROJECTIONS = ("ortho", "equirect")


def check_dot_radius_style(dot_style, dot_radius):
    """Refuse a ``dot_radius`` for point dots: a point is one short pen stroke, which the radius does not size
    (it only let the dots touch)."""
    if dot_radius is not None and dot_style == "point":
        from ..errors import StippleError

        raise StippleError("--dot-radius does not size --dot-style point (one short pen stroke): it would be ignored")
