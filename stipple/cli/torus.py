"""``stipple torus``: an image's dots on the torus."""

import time

import click

from ..errors import StippleError
from ..io.commit import output_format
from ..io.images import load_input
from ..io.png import check_png_outputs
from ..io.points import read_torus_init
from ..plotter import physical_centres
from ..transforms import BACKENDS
from .options import common_options, init_input, palette_options, render_settings, resolve_input
from .supervise import finish, guarded_files, plot_order, solve, write_outputs


@click.command()
@click.argument("image", required=False)
@common_options
@click.option(
    "--init",
    default="stratified",
    show_default=True,
    help="Start: 'stratified' (the image's dots shared out along a Hilbert curve), 'density' (i.i.d. from the "
    "image), 'uniform', or a CSV of x,y pixel positions.",
)
@click.option("--backend", type=click.Choice(BACKENDS), default="ducc0", show_default=True, help="NUFFT library.")
@click.option(
    "--hessian",
    type=click.Choice(["gauss-newton", "full"]),
    default="gauss-newton",
    show_default=True,
    help="Hessian of the Newton step (and of --beta daniel).",
)
@click.option(
    "--correct/--no-correct",
    default=True,
    show_default=True,
    help="Finish with the low-frequency correction (a few iterations of the plain E_N at N/6 and N/12; README, "
    "Defaults).",
)
@palette_options(None)
@click.pass_context
def torus(ctx, image, **options):
    """Stipple IMAGE (PNG, JPEG, TIFF, ..., or a .npy map; '-' for stdin) on the torus; with --palette, one
    layer of dots per ink (as 'stipple colour')."""
    from ..io.writers import torus_output
    from ..torus import DEFAULT_EPSILON, torus_problem

    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    if options["palette"] is not None:
        from .colour import run_colour

        return run_colour(image, options, started)
    try:
        settings = render_settings(options)
        inputs = [("image", image), init_input(options["init"])]
        with guarded_files([i for i in inputs if i], options["outputs"], options["checkpoint"]):
            weights = load_input(
                image, invert=options["invert"], gamma=options["gamma"], value_range=options["value_range"]
            )
            check_png_outputs(
                [output_format(path) for path in options["outputs"]],
                weights.shape[::-1],
                options["png_width"],
                options["n_points"],
            )
            problem = torus_problem(
                weights,
                options["n_points"],
                options["bandwidth"],
                backend=options["backend"],
                threads=options["threads"],
                epsilon=DEFAULT_EPSILON if options["epsilon"] is None else options["epsilon"],
                hessian=options["hessian"],
                near_field=options["near_field"] is not False,
            )
            result, stopped_by = solve(problem, options, read_torus_init(options["init"], weights.shape))
            points = plot_order(
                physical_centres(result.points, weights.shape, settings["width"]),
                result.points,
                options,
                settings["width"][1],
            )
            write_outputs(
                options["outputs"],
                lambda fmt: torus_output(points, weights.shape, fmt, darkness=weights, **settings),
            )
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)
