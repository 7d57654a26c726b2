"""``stipple torus``: an image's dots on the torus."""

import time

import click
import numpy as np

from ..batch import TorusRecipe, draw_image
from ..errors import StippleError
from ..io.commit import output_format
from ..io.images import load_input
from ..io.points import read_torus_init
from ..transforms import BACKENDS
from .options import common_options, init_input, palette_options, parse_levels, render_settings, resolve_input
from .pen import pen_count_recipe, pen_points, pen_problem
from .supervise import finish, guarded_files, solve, write_outputs


@click.command()
@click.argument("image", required=False)
@common_options(auto_count=True)
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
@click.option(
    "--levels",
    default=None,
    help="Images: gray values BLACK,WHITE in [0, 1] stretched to black and white before stippling, or 'auto' "
    "(the 0.5th and 99.5th percentiles): a faint document's strokes get the full range (docs/picture.md).",
)
@palette_options(None)
@click.pass_context
def torus(ctx, image, **options):
    """Stipple IMAGE (PNG, JPEG, TIFF, ..., or a .npy map; '-' for stdin) on the torus; with --palette, one
    layer of dots per ink (as 'stipple colour')."""
    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    if options["palette"] is not None:
        from .colour import run_colour

        if options["n_points"] == "auto":
            raise click.ClickException("-M auto is for one ink (stipple torus without --palette)")

        return run_colour(image, options, started)
    try:
        recipe = torus_recipe(options)
        width = recipe.draw["width"]
        inputs = [("image", image), init_input(options["init"])]
        with guarded_files([i for i in inputs if i], options["outputs"], options["checkpoint"]):
            weights = load_input(image, **recipe.load)
            tone_hints(weights, options)
            recipe = pen_count_recipe(recipe, weights, options)
            problem = pen_problem(weights, [output_format(path) for path in options["outputs"]], recipe, options)
            result, stopped_by = solve(problem, options, read_torus_init(options["init"], weights.shape))
            points = pen_points(result.points, problem, weights.shape, width, options)
            write_outputs(options["outputs"], lambda fmt: draw_image(points, weights, [fmt], recipe)[fmt])
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)


def torus_recipe(options):
    """What ``stipple torus`` does to an image with these options, as a ``stipple.batch.TorusRecipe`` (the
    run's stopping, checkpoint and progress options are ``solve``'s)."""
    from ..torus import DEFAULT_EPSILON

    return TorusRecipe(
        load={
            "invert": options["invert"],
            "gamma": options["gamma"],
            "value_range": options["value_range"],
            "levels": parse_levels(options["levels"]),
        },
        problem={
            "n_points": options["n_points"],
            "bandwidth": options["bandwidth"],
            "backend": options["backend"],
            "threads": options["threads"],
            "epsilon": DEFAULT_EPSILON if options["epsilon"] is None else options["epsilon"],
            "hessian": options["hessian"],
            "near_field": options["near_field"] is not False,
        },
        solve={
            "init": options["init"],
            "seed": options["seed"],
            "tol": options["tol"],
            "iterations": options["iterations"],
            "time_limit": options["time_limit"],
            "safeguard": options["safeguard"],
            "beta": options["beta"],
            "correct": options["correct"],
            "settle": options["settle"],
        },
        draw=render_settings(options),
        order=bool(options["order"]),
    )


# Hints on stderr, never a silent change: a faint document (its gray values span less than this) and a mostly
# dark image (mean darkness above this) are drawn as they are, with the option that would help named.
FAINT_SPAN, DARK_MEAN = 0.6, 0.75


def tone_hints(weights, options):
    """One line each for a faint or a mostly dark input, unless --quiet, --levels or --invert was given."""
    if options["quiet"] or options["levels"] is not None or options["invert"]:
        return
    low, high = np.percentile(weights, [0.5, 99.5])
    if high - low < FAINT_SPAN:
        click.echo(
            f"stipple: note: the image's gray values span only {high - low:.0%} of the range; drawn as they are "
            "(--levels auto stretches them to black and white: docs/picture.md)",
            err=True,
        )
    if weights.mean() > DARK_MEAN:
        click.echo(
            f"stipple: note: the image is {weights.mean():.0%} dark on average; drawn dark as it is (--invert draws "
            "its light parts as white dots on black: docs/picture.md)",
            err=True,
        )
