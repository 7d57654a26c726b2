"""The pen plotter's part of ``stipple torus``: ``-M auto`` from the pen (``stipple.pen_count``) and
``--order progressive`` (``stipple.progressive``), wired into the command."""

import click
import numpy as np

from ..batch import image_problem
from ..plotter import physical_centres
from .supervise import plot_order


def pen_problem(weights, formats, recipe, options):
    """The run's problem: the image's, or with ``--order progressive`` the nested levels' (``stipple.progressive``)."""
    if options["order"] != "progressive":
        return image_problem(weights, formats, recipe)
    from ..io.png import check_png_outputs
    from ..progressive import progressive_problem

    settings = dict(recipe.problem)
    n_points = settings.pop("n_points")
    check_png_outputs(formats, weights.shape[::-1], recipe.draw.get("png_width"), n_points)
    return progressive_problem(weights, n_points, settings.pop("bandwidth", None), **settings)


def pen_points(points, problem, shape, width, options):
    """``points`` in their plotting order: ``--order`` one short path, ``--order progressive`` pass by pass."""
    centres = physical_centres(points, shape, width)
    if options["order"] != "progressive":
        return plot_order(centres, points, options, width[1])
    from ..progressive import progressive_order

    counts = np.diff([0] + [part.stop for part in problem.slices])
    order, before, after = progressive_order(centres, counts)
    if not options["quiet"]:
        passes = ", ".join(str(count) for count in counts)
        message = f"pen-up travel {before:.4g} -> {after:.4g} {width[1]} in passes of {passes} dots"
        click.echo(f"stipple: {message}", err=True)
    return points[order]


def pen_count_recipe(recipe, weights, options):
    """The recipe with ``-M auto`` resolved from the pen (``stipple.pen_count``); the choice on stderr and in
    the SVG's notes."""
    if options["n_points"] != "auto":
        return recipe
    from dataclasses import replace

    from ..io.units import UNITS
    from ..pen_count import auto_count

    draw = recipe.draw
    millimetres = [value * UNITS[unit] for value, unit in (draw["width"], draw["pen_width"])]
    count = auto_count(weights, millimetres[0], draw["dot_style"], millimetres[1])
    lines = [count.reason()] + [line for line in (count.note(),) if line]
    if not options["quiet"]:
        for line in lines + ([count.details()] if options["verbose"] else []):
            click.echo(f"stipple: {line}", err=True)
    options["n_points"] = count.n_points
    return replace(
        recipe,
        problem={**recipe.problem, "n_points": count.n_points},
        draw={**draw, "notes": (*draw.get("notes", ()), *lines)},
    )
