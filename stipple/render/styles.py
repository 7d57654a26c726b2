"""The drawing's named choices (no numpy: the command line shows them in ``--help``)."""

# How dots are sized: "tone" (tone-true radii, ``stipple.tone``) or "plotter" (one radius, capped so no two touch).
STYLES = ("tone", "plotter")
# Pen paths a plotter draws for a dot (``stipple.render.pen.dot_paths``); "disc" is a filled disc, no path.
DOT_STYLES = ("circle", "filled", "point")
# Pictures of sphere points: the orthographic globe or the equirectangular map.
PROJECTIONS = ("ortho", "equirect")
