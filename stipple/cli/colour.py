"""``stipple colour``: one class of dots per ink of a colour image, optimised jointly."""

import time

import click

from ..errors import StippleError
from ..io.commit import output_format
from .defaults import BACKENDS, INITS
from .options import common_options, palette_options, render_settings, resolve_input
from .supervise import finish, guarded_files, plot_order, solve, write_outputs


@click.command()
@click.argument("image", required=False)
@common_options
@palette_options("cmyk")
@click.option("--init", type=click.Choice(INITS), default="density", show_default=True)
@click.option("--backend", type=click.Choice(BACKENDS), default="ducc0", show_default=True, help="NUFFT library.")
@click.option("--hessian", type=click.Choice(["gauss-newton", "full"]), default="gauss-newton", show_default=True)
@click.pass_context
def colour(ctx, image, **options):
    """Stipple a colour IMAGE with one layer of dots per ink (CSV x,y,layer; SVG one layer per pen)."""
    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    run_colour(image, options, started)


def run_colour(image, options, started):
    """Separate, optimise jointly and write one layer per ink (``stipple colour``, ``stipple torus --palette``)."""
    import numpy as np

    from ..colour import colour_problem, parse_palette
    from ..io.images import load_colour
    from ..io.writers import layered_torus_output
    from ..torus import DEFAULT_EPSILON

    try:
        check_colour_options(options)
        palette = parse_palette(options["palette"])
        settings = render_settings(options)
        settings.pop("color")
        with guarded_files([("image", image)], options["outputs"], options["checkpoint"]):
            rgb = load_colour(image)
            check_png(options, rgb.shape[1::-1])
            layers, problem = colour_problem(
                rgb,
                options["n_points"],
                options["bandwidth"],
                separation=palette,
                black=options["black"],
                union_weight=options["union_weight"],
                backend=options["backend"],
                threads=options["threads"],
                epsilon=DEFAULT_EPSILON if options["epsilon"] is None else options["epsilon"],
                hessian=options["hessian"],
                near_field=options["near_field"] is not False,
            )
            result, stopped_by = solve(problem, options, options["init"])
            shape = rgb.shape[:2]
            placed = [
                (layer.name, layer.colour, ordered(result.points[part], shape, settings, options))
                for layer, part in zip(layers, problem.slices, strict=True)
            ]
            ink = sum(layer.density for layer in layers).mean()
            coverages = [np.clip(layer.density, 0.0, 1.0) for layer in layers]
            write_outputs(
                options["outputs"],
                lambda fmt: layered_torus_output(
                    placed, shape, fmt, ink=ink, coverages=coverages, target=rgb, **settings
                ),
            )
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)


def check_colour_options(options):
    """Options of the shared set that have no meaning for colour separation are refused, not ignored."""
    if options["init"] not in INITS:
        raise StippleError(
            "--init must be stratified, density or uniform for colour separation (a start CSV is for one class); "
            "stratified starts from i.i.d. samples of each ink"
        )
    if options["invert"] or options["value_range"] is not None:
        raise StippleError("--invert and --range are for gray images and maps, not colour separation")
    if options["gamma"] != 1.0 or options.get("levels") is not None:
        raise StippleError("--gamma and --levels are for gray images and maps, not colour separation")
    if options["color"] is not None or options["background"] is not None:
        raise StippleError("--color and --background are for one-colour dots; colour separation prints on white paper")


def check_png(options, canvas):
    """Refuse, before the run, a PNG output too large to draw: the inks' picture holds about 33 bytes a pixel."""
    from ..io.png import check_png_canvas, default_png_width

    if ".png" in [output_format(path) for path in options["outputs"]]:
        check_png_canvas(canvas, options["png_width"] or default_png_width(options["n_points"]), layers=33)


def ordered(points, shape, settings, options):
    """One layer's points, along a short pen path when ``--order`` is given (each pen draws its own layer)."""
    if len(points) < 2:
        return points
    from ..render.pen import physical_centres

    centres = physical_centres(points, shape, settings["width"])
    return plot_order(centres, points, options, settings["width"][1])
