"""The pen plotter's part of one image's pipeline (``stipple.pipelines.image``): ``-M auto``, the dot count from
the pen and the paper (``stipple.render.pen_count``), and the plotting order: one short pen path (``--order``)
or nested passes (``--order progressive``, ``stipple.progressive``)."""

from dataclasses import replace

import numpy as np

from ..render.pen import pen_order, physical_centres
from ..render.pen_count import PEN_STYLES, auto_count, clipped_density, packing_ratio, paper_and_pen, pen_density

ORDERS = ("path", "progressive")


def order_kind(order):
    """The recipe's ``order`` as None, "path" or "progressive" (``True`` is "path", as a bare ``--order``)."""
    if not order:
        return None
    if order is True or order == "path":
        return "path"
    if order == "progressive":
        return order
    raise ValueError(f"order must be one of {', '.join(ORDERS)}, not {order!r}")


def counted_recipe(recipe, weights):
    """``(recipe, count)``: with ``n_points`` "auto", the recipe with M chosen from the pen (``count``, a
    ``stipple.render.pen_count.PenCount``, whose reason and note go to the SVG's notes as data); else
    ``(recipe, None)``."""
    if recipe.problem.get("n_points") != "auto":
        return recipe, None
    draw = recipe.draw
    paper, pen = paper_and_pen(draw)
    count = replace(auto_count(weights, paper, draw["dot_style"], pen), inverted=bool(recipe.load.get("invert")))
    lines = [line for line in (count.reason(), count.note()) if line]
    recipe = replace(
        recipe,
        problem={**recipe.problem, "n_points": count.n_points},
        draw={**draw, "notes": (*draw.get("notes", ()), *lines)},
    )
    return recipe, count


def placement_density(weights, n_points, draw):
    """The density ``n_points`` dots drawn with ``draw`` (the render settings) are placed by: ``weights``, or for
    pen dots in the plotter style (whose dots must never touch) the same clipped where the dots would pack closer
    than the pen allows (``stipple.render.pen_count.pen_density``); also the ink the drawing's dots carry (a
    filled dot's radius), in the run's drawing and in ``stipple render --like``."""
    if not clipped_for_the_pen(draw):
        return weights
    paper, pen = paper_and_pen(draw)
    return pen_density(weights, n_points, paper, draw["dot_style"], pen)


def clipped_for_the_pen(draw):
    """Whether the drawing ``draw`` (the render settings) places its dots by a density clipped for the pen: pen
    dots in the plotter style, at the radius that keeps them apart (not a fixed ``dot_radius``)."""
    return draw.get("dot_style") in PEN_STYLES and draw.get("dot_radius") is None and draw.get("style") == "plotter"


def sphere_pen_density(density, n_points, draw, projection):
    """A sphere map's density as pen dots in the plotter style are placed by: clipped where they would pack
    closer on the drawing than the pen allows (``clipped_density`` over the map's cells, at the drawing's
    millimetres per radian: the map's along a meridian, the globe's at its centre, where foreshortening and the
    map's stretch only part them further), as ``placement_density`` clips an image's. Other densities and
    styles: unchanged. Without it a map's dense regions left dots out (the topography at M = 5000, a 0.5 mm pen,
    100 mm wide: 556 of 5000)."""
    from ..render.dots import sphere_per_radian
    from ..sphere_density import CellMap

    if not clipped_for_the_pen(draw) or not isinstance(density, CellMap):
        return density
    paper_width, pen_width = paper_and_pen(draw)
    sphere_paper = 4 * np.pi * sphere_per_radian(projection, paper_width) ** 2  # mm² at the drawing's scale
    allowed = packing_ratio(draw["dot_style"], pen_width, sphere_paper, n_points)
    values = clipped_density(density.values, allowed, density.cell_areas)
    return density if values is density.values else CellMap(values, density.lon0)


def ordered_points(points, problem, shape, recipe):
    """``(points, travel, passes)``: ``points`` in plotting order (as they are without ``recipe.order``), the
    pen-up travel ``(before, after, None)`` in the unit of the drawing's width, and the dots per pass (progressive)."""
    kind = order_kind(recipe.order)
    if kind is None:
        return points, [], []
    centres = physical_centres(points, shape, recipe.draw.get("width", (200.0, "mm")))
    if kind == "path":
        points, before, after = pen_order(points, centres)
        return points, [(before, after, None)], []
    from ..progressive import progressive_order

    counts = [int(count) for count in np.diff([0] + [part.stop for part in problem.slices])]
    order, before, after = progressive_order(centres, counts)
    return points[order], [(before, after, None)], counts
