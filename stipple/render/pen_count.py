"""``-M auto``: the number of dots that a pen of a given width draws the image's ink with on a given paper.

A pen dot inks a fixed area ``a``: for the "point" style one pen touch, a disc of the pen's diameter ``w`` swept
along the point's stroke of ``w / 10`` (``a = (pi / 4 + 1 / 10) w^2``); for "filled" and "circle" the smallest
dot of the style, a pen circle of radius ``w / 2`` (pen centre), which inks a disc of radius ``w`` (``a = pi
w^2``; the plotter style's tone radius is then exactly ``w``). M dots carry the image's ink when ``M a`` is its
total darkness times the paper's area: ``M_tone = mean(w) A / a``.

The plotter style never lets two dots touch: a filled or circle dot's radius is at most ``TOUCH_FRACTION`` of
its distance to its nearest neighbour, and a point dot's reach is ``r = w / 2`` (a filled or circle dot of the
tone radius for ``-M auto`` reaches ``r = w``); a pen dot is never smaller than its path's least reach
(``stipple.render.dots.least_pen_reach``), so dots closer than that over ``TOUCH_FRACTION`` are thinned out of
the drawing (``stipple.render.dots.thin_apart``). Packed hexagonally at the limit ``r / TOUCH_FRACTION``, dots
cover ``a 2 f^2 / (sqrt(3) r^2)`` of the paper (0.83 for points, 0.73 for filled and circle dots). An optimised
stipple is not a lattice: its nearest neighbours are closer than the
hexagonal spacing (5 % of them closer than ``NEIGHBOUR_RATIO`` of it), and there dots shrink (filled and circle)
or are left out (every style), so the tones saturate earlier: at ``NEIGHBOUR_RATIO^2`` of the lattice's cover
(0.49 for filled and circle dots, measured on flat grays: drawn 0.50 for 0.5, 0.44 to 0.57 beyond; 0.56 for
points, which before the thinning overlapped to draw 0.41, 0.51, 0.62, 0.72, 0.81 for 0.4 to 0.8, touching). That
coverage ``c_max`` is the darkest tone the pen draws, and at most ``M_pack = c_max A / a`` dots fit on the paper.
``-M auto`` counts the ink of the darkness clipped at ``c_max``, ``M = mean(min(w, c_max)) A / a`` (at most
``M_pack``), and ``pen_density`` places the dots by that clipped density (for a given M, clipped where the dots
would pack closer than the limit): tones darker than ``c_max`` are drawn at ``c_max``, evenly, without a dot left
out, and the lighter ones keep their tone.
"""

from dataclasses import dataclass

import numpy as np

from ..errors import StippleError
from ..halftone import MAX_POINTS
from ..io.units import UNITS
from .dots import TOUCH_FRACTION

PEN_STYLES = ("point", "filled", "circle")
# The 5th percentile of nearest-neighbour distance / hexagonal spacing of an optimised stipple (0.822 for 2264
# dots of the cameraman).
NEIGHBOUR_RATIO = 0.82
DARKEST_PERCENTILE = 99.0
# The share of the dots that carry the ink the pen reaches that -M auto takes. Filled and circle dots at the full
# count fill the no-touch packing in the darkest tones, and where an optimised stipple's neighbours come closer than
# the lattice's those dots shrink to the pen's least dot or are left out, so the picture there comes out flat and
# light: a held-out portrait (1 mm pen, 200 mm) drew luminance RMSE 0.122 at sigma 4 px at the full count, 0.080
# at 0.74-0.89 of it and 0.102 at 0.96; with a 0.5 mm pen, 150 mm, 0.122 against 0.079 at 0.8, and a dark photo
# 0.380 against 0.289 at 0.9. Point dots (a fixed area each) drew best at the full count (0.090; 0.109 at 0.9).
AUTO_SHARE = {"point": 1.0, "filled": 0.85, "circle": 0.85}
# The words of the unreachable tones' note: black dots on paper, and light dots on a dark ground (--invert).
TONE_WORDS = ("darker", "lighter", "darkest", "dark")
INVERTED_WORDS = ("lighter", "darker", "lightest", "light")


@dataclass
class PenCount:
    """The chosen M and why: areas in mm², ``darkest`` the image's 99th-percentile darkness, ``reachable`` the
    darkest tone the style's no-touch packing draws."""

    n_points: int
    tone_points: int
    packing_points: int
    dot_area: float
    ink_area: float
    paper_area: float
    reachable: float
    darkest: float
    inverted: bool = False  # light dots on a dark ground (--invert): the light tones are the ones out of reach
    carried_points: int = 0  # the dots that carry the ink the pen reaches (``n_points`` is ``AUTO_SHARE`` of them)

    @property
    def capped(self):
        return self.n_points < self.tone_points

    def reason(self):
        """One line: the chosen M and why."""
        if self.capped:
            beyond = INVERTED_WORDS[0] if self.inverted else TONE_WORDS[0]
            why = (
                f"the ink of the tones the pen reaches without touching, {beyond} ones drawn at "
                f"{self.reachable:.0%} ({self.tone_points} would carry all the ink)"
            )
        else:
            why = f"{self.ink_area:.4g} mm² of ink / {self.dot_area:.4g} mm² per pen dot"
        if self.n_points < self.carried_points:
            why = (
                f"{self.n_points / self.carried_points:.0%} of the {self.carried_points} that carry {why}, so that "
                "the closest dots keep their size"
            )
        return f"-M auto: {self.n_points} dots, {why}"

    def note(self):
        """A line when the image's darkest tones are beyond the packing's reach, else None."""
        why = "the pen's dots cannot pack closer without touching"
        return out_of_reach(self.reachable, self.darkest, self.inverted, why)

    def details(self):
        """The numbers behind the choice (for ``-v``)."""
        return (
            f"paper {self.paper_area:.6g} mm², ink {self.ink_area:.6g} mm², pen dot {self.dot_area:.4g} mm², "
            f"tone count {self.tone_points}, packing count {self.packing_points}, darkest reachable tone "
            f"{self.reachable:.3f}"
        )


def pen_dot(style, pen_width):
    """``(area, reach)`` in mm² and mm of one pen dot of ``style`` drawn with a pen ``pen_width`` mm wide."""
    if style == "point":
        return (np.pi / 4 + 0.1) * pen_width**2, pen_width / 2
    if style in ("filled", "circle"):
        return np.pi * pen_width**2, pen_width
    raise StippleError(f"-M auto needs a pen dot style ({', '.join(PEN_STYLES)}), not --dot-style {style}")


def reachable_tone(style, pen_width=1.0):
    """The darkest coverage of the style's dots under the plotter style's no-touch rule (module docstring)."""
    area, reach = pen_dot(style, pen_width)
    spacing = reach / TOUCH_FRACTION
    return area * 2 / (np.sqrt(3) * spacing**2) * NEIGHBOUR_RATIO**2


def paper_area(paper_width, shape):
    """The area (mm²) of paper ``paper_width`` mm wide with an image of ``shape = (H, W)``'s aspect."""
    rows, columns = shape
    return paper_width * paper_width * rows / columns


def packing_count(style, pen_width, paper):
    """``M_pack``: the most dots of ``style`` a pen ``pen_width`` mm wide draws on ``paper`` mm² without touching."""
    return int(np.floor(reachable_tone(style, pen_width) * paper / pen_dot(style, pen_width)[0]))


def paper_and_pen(draw):
    """The drawing's width and pen width in mm from the render settings ``draw`` (``(value, unit)`` lengths)."""
    return tuple(value * UNITS[unit] for value, unit in (draw["width"], draw["pen_width"]))


def auto_count(darkness, paper_width, style, pen_width):
    """The ``PenCount`` of a density ``darkness`` (H, W) in [0, 1] drawn ``paper_width`` mm wide.

    Raises
    ------
    StippleError
        For a disc style, an image without ink, or a count beyond ``MAX_POINTS``.
    """
    darkness = np.asarray(darkness, dtype=np.float64)
    paper, area, packing_points, carried = pen_capacity(darkness, paper_width, style, pen_width)
    ink = float(darkness.mean()) * paper
    reachable = reachable_tone(style, pen_width)
    tone_points = int(round(ink / area))
    count = auto_points(style, carried)
    if count < 1:
        raise StippleError(
            f"-M auto: the image's ink ({ink:.3g} mm²) is less than one pen dot ({area:.3g} mm²); give -M"
        )
    if count > MAX_POINTS:
        raise StippleError(
            f"-M auto: {count} dots of a {pen_width:g} mm pen on this paper is more than {MAX_POINTS}; use a "
            "wider pen, a smaller --width or give -M"
        )
    darkest = float(np.percentile(darkness, DARKEST_PERCENTILE))
    return PenCount(
        count, tone_points, packing_points, area, ink, paper, float(reachable), darkest, carried_points=carried
    )


def pen_capacity(darkness, paper_width, style, pen_width):
    """``(paper, area, packing, carried)``: the paper's mm², a pen dot's, the most dots that fit without touching
    (``packing_count``) and the dots that carry the ink the pen reaches (``carried_count``)."""
    paper = paper_area(paper_width, darkness.shape)
    area, _ = pen_dot(style, pen_width)
    packing = packing_count(style, pen_width, paper)
    return paper, area, packing, carried_count(darkness, reachable_tone(style, pen_width), paper, area, packing)


def auto_points(style, carried):
    """``-M auto``'s count of ``style``'s dots: ``AUTO_SHARE`` of the ``carried`` that carry the ink."""
    return int(round(AUTO_SHARE[style] * carried))


def carried_count(darkness, reachable, paper, area, packing):
    """The dots of pen dot ``area`` (mm²) that carry the ink the pen can lay on ``paper`` mm² (tones beyond
    ``reachable`` drawn at it, as ``pen_density`` places them), at most ``packing``: ``-M auto``'s count."""
    return min(int(round(float(np.minimum(darkness, reachable).mean()) * paper / area)), packing)


def pen_density(darkness, n_points, paper_width, style, pen_width):
    """The density to place ``n_points`` pen dots by (``paper_width`` mm wide, a pen ``pen_width`` mm wide) so
    that nowhere are they asked to pack closer than the no-touch packing allows: ``darkness`` clipped at the level
    ``c`` at which the clipped regions' dots cover ``reachable_tone`` (``c / mean(min(w, c))`` is the densest
    dots' density over the mean; it grows with ``c``, and the packing allows ``reachable_tone * paper / (M a)``).
    Unchanged where the dots nowhere need to be that dense. Without it the stipple's darkest regions held dots
    closer than a pen dot allows, which the drawing had to leave out (``stipple.render.dots.thin_apart``),
    irregularly: a dark photo's darkest tenth came out 0.35 dark, against the 0.56 that the packing reaches."""
    darkness = np.asarray(darkness, dtype=np.float64)
    paper = paper_area(paper_width, darkness.shape)
    return clipped_density(darkness, packing_ratio(style, pen_width, paper, n_points))


def packing_ratio(style, pen_width, paper, n_points):
    """How much denser than on average ``n_points`` pen dots of ``style`` may pack on ``paper`` mm² without
    touching: ``reachable_tone * paper / (M a)``."""
    return reachable_tone(style) * paper / (n_points * pen_dot(style, pen_width)[0])


def clipped_density(darkness, allowed, cell_areas=None):
    """``darkness`` clipped at the level ``c`` with ``c / mean(min(w, c)) = allowed`` (means weighted by
    ``cell_areas``, default equal): the densest dots at ``allowed`` times the mean density (``pen_density``;
    the sphere's cells, ``stipple.pipelines.pen.sphere_pen_density``). Unchanged where it is nowhere that dense."""

    def mean(values):
        return float(np.average(values, weights=cell_areas))

    if mean(darkness) <= 0 or darkness.max() <= allowed * mean(darkness):
        return darkness
    # Bisection of c / mean(min(w, c)) = allowed; as c falls the clip tends to an even density over the inked
    # cells, whose ratio (1 / their share) no fewer dots can go below.
    # The levels are searched between the least positive value (where the ratio is that bound) and the largest,
    # halving their ratio: a map of a narrow Gaussian needed a level of 1e-35, which 60 halvings of [0, max]
    # could not reach (it stayed unclipped, and the pen drawing left 1399 of 1500 dots out).
    target = max(allowed, 1.0 / mean(darkness > 0))
    low, high = float(darkness[darkness > 0].min()), float(darkness.max())
    for _ in range(200):
        level = np.sqrt(low * high)
        if not low < level < high:
            break
        if level > target * mean(np.minimum(darkness, level)):
            high = level
        else:
            low = level
    return np.minimum(darkness, low)


# A point pen's dots with a given -M that carry less than this share of the image's ink get a note; pen dots of any
# style more than -M auto's count get one too.
LIGHT_SHARE = 0.8


def out_of_reach(reachable, darkest, inverted, why, advice=""):
    """The line saying that the image's tones beyond ``reachable`` (the no-touch packing's darkest tone) come out
    lighter, ``why``, where its ``darkest`` (99th percentile) is beyond it, else None; ``inverted``: light dots
    on a dark ground, whose darkness is the image's lightness (its lightest tones come out darker)."""
    if darkest <= reachable:
        return None
    beyond, drawn, extreme, tone = INVERTED_WORDS if inverted else TONE_WORDS
    return (
        f"tones {beyond} than {reachable:.0%} will be {drawn}: {why} (the image's {extreme} 1 % is {darkest:.0%} "
        f"{tone}{advice})"
    )


def given_count_notes(darkness, n_points, draw, inverted=False):
    """Lines about a drawing of ``n_points`` dots in a pen or plotter style (``draw``: the render settings): tones
    darker than the no-touch packing reaches come out lighter (as ``-M auto`` says), and a point pen's dots (a
    fixed area each) that carry far less than the image's ink draw a lighter picture (``-M 8000`` of a 0.5 mm pen
    drew a 2:1 photo's mean darkness 0.61 as 0.08). ``inverted``: light dots on a dark ground (``--invert``),
    whose ``darkness`` is the image's lightness: the lightest tones are the ones that come out darker."""
    style = draw["dot_style"]
    if draw.get("dot_radius") is not None or not (style in PEN_STYLES or draw.get("style") == "plotter"):
        return []
    darkness = np.asarray(darkness, dtype=np.float64)
    lines = []
    reachable = reachable_tone(style if style in PEN_STYLES else "filled")
    darkest = float(np.percentile(darkness, DARKEST_PERCENTILE))
    why, advice = "the plotter style's dots never touch", "; the default tone style with discs draws them"
    line = out_of_reach(reachable, darkest, inverted, why, advice)
    if line:
        lines.append(line)
    if style in PEN_STYLES:
        lines += pen_count_notes(darkness, n_points, draw, inverted)
    return lines


def pen_count_notes(darkness, n_points, draw, inverted=False):
    """``given_count_notes``' lines on the count of pen dots: too few point dots for the image's ink, more than
    fit without touching, and, for every style, more than carry the ink the pen reaches (``carried_count``): a
    point dot inks a fixed area, so more of them draw the light tones darker (-M 4500 of a 0.5 mm pen, against
    4081, drew a held-out portrait's 0.72 luminance as 0.64); filled and circle dots packed closer are placed more
    evenly and drawn smaller (-M 8000 of a 1 mm pen, against 6744, drew the portrait a flat light gray: luminance
    RMSE 0.27 at 4 px, against 0.08 at -M auto's ``AUTO_SHARE`` of them)."""
    style = draw["dot_style"]
    paper_width, pen_width = paper_and_pen(draw)
    paper, area, packing, carried = pen_capacity(darkness, paper_width, style, pen_width)
    light, dark = (INVERTED_WORDS if inverted else TONE_WORDS)[1::-1]
    dots = f"{n_points} {style} dots of a {pen_width:g} mm pen"
    if style == "point" and n_points < LIGHT_SHARE * carried:
        return [
            f"{dots} ink {n_points * area / paper:.0%} of the paper for the image's {darkness.mean():.0%}: the drawing "
            f"comes out {light} (-M auto counts the dots that carry its ink, {carried})"
        ]
    if n_points <= carried:
        return []
    if style != "point":
        auto = auto_points(style, carried)
        return [
            f"{dots} are more than the {carried} that carry the image's ink without touching (-M auto takes {auto}): "
            f"packed closer, they are placed more evenly and drawn smaller, and the picture comes out flatter and "
            f"{light}"
        ]
    if n_points <= packing:
        why = f"its {light} tones come out {dark}"
        return [f"{dots} are more than the {carried} that carry the image's ink (-M auto): {why}"]
    return [
        f"{dots} are more than the {packing} that fit on this paper without touching: the drawing leaves out those "
        "that would touch (give fewer, or -M auto)"
    ]


def ink_darkness(image, separation="gray", black=1.0):
    """The total ink density (H, W) of an image file over its inks (``stipple.colour.separate``): what
    ``auto_count`` counts dots for when every ink is drawn with the same pen."""
    from ..colour import separate, union_darkness
    from ..io.images import load_colour

    return union_darkness(separate(load_colour(image), separation, black))
