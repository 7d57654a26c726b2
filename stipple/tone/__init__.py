"""Tone-true dot radii: the drawn ink, as a viewer sees it, has the image's darkness where each dot sits.

A dot of the same radius everywhere, capped so that no two dots touch (``stipple.render.dots``), covers at most
about 73 % of the paper, so dark tones come out gray. Here each dot gets its own radius: dots grow, and may
overlap, where the image is dark, and shrink where it is light.

Every dot owns its Voronoi cell (the points of the canvas nearer to it than to any other dot), and its radius
is chosen so that the ink inside its cell, the union of all discs (overlapping discs do not add ink twice),
covers the cell's mean darkness. The cells tile the canvas, so the ink then matches the darkness on every
scale above a cell, whatever blur a viewer's eye applies. (Comparing a blurred drawing with the darkness at the
dots themselves would be biased: a dot always covers the place where it sits.)

1. Cells on a grid of about ``samples_per_dot`` pixels per dot (a Euclidean distance transform from the dots'
   pixels), each cell's area ``A`` and mean darkness ``t``.
2. First radii from a model of the union of blue-noise discs: discs of radius ``r`` at density ``rho`` have the
   ink ratio ``x = rho pi r^2`` and cover the fraction ``f(x) = x (1 + x^n)^(-1/n)`` of the paper
   (``union_coverage``; ``n = 9.55`` fits ``stipple``'s own blue noise within 0.01: discs cover as much as
   they would apart up to ``x`` near 0.7, and the paper is black, to 0.2 %, at ``x = 1.4``, a radius of 0.62
   times the hexagonal spacing). So ``pi r^2 = f^-1(t) A``.
3. ``passes`` corrections against the drawing itself: the union of the discs is drawn (``union_coverage_image``
   at ``analysis_supersample`` fine pixels a grid pixel), each cell's covered fraction ``c`` measured, and each
   radius multiplied by ``(f^-1(t) / f^-1(c))^(0.7 / 2)``, bounded to ``[1/2, 2]``: a damped Newton step in
   the model, monotone in the error (undamped, cells oscillate where discs begin to touch).
4. Radii stay within ``[min_radius, max_radius]`` and at most ``max_ratio`` times the distance to the nearest
   other dot, so that no dot swallows its neighbours.

Inks printed on white paper multiply: each channel's reflectance is the product over inks of
``1 - m_k (1 - p_k)`` (``m_k`` whether ink ``k`` covers the point, ``p_k`` its colour; ``multiply_picture``
draws exactly that). ``stipple.colour.separate`` assumes that dots of different inks never overlap, so that
coverages add; but its coverages add up to more than 1 wherever a colour is dark and saturated, and where
they overlap, multiplied, they print too light and too grey. ``multiply_separation`` gives coverages that
print the image's colour when the inks are laid independently of each other (for cyan, magenta and yellow
alone, ``c = 1 - R``, exactly, however the dots overlap). Dots of a joint stipple are neither apart nor
independent, so ``tone_radii_layers`` with the inks' colours corrects against the drawn colour itself.

A torus's picture wraps around (``periodic``, ``stipple.tone.wrap``): its dots near an edge have neighbours and
ink across the opposite edge. ``fit_inside`` keeps every dot of a picture that does not wrap on the canvas without
moving the others (``stipple.render.dots.inset`` shrinks the whole drawing, a misregistration of up to one radius
that a blurred comparison counts as tone error).

Modules: ``radii`` (the radii and ``fit_inside``), ``raster`` (the drawn union and inks, from
``stipple.io.raster``'s exact discs), ``inks`` (separations for multiplying inks), ``wrap`` (the periodic canvas),
``checks`` (argument checks). The library uses numpy, scipy and Pillow only.
"""

from .inks import INK_COLOURS, multiply_colour, multiply_separation
from .radii import fit_inside, ink_ratio, tone_radii, tone_radii_layers, union_coverage
from .raster import multiply_picture, union_coverage_image

__all__ = [
    "INK_COLOURS",
    "fit_inside",
    "ink_ratio",
    "multiply_colour",
    "multiply_picture",
    "multiply_separation",
    "tone_radii",
    "tone_radii_layers",
    "union_coverage",
    "union_coverage_image",
]
