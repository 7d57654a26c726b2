"""``stipple torus``: an image's dots on the torus."""

import time

import click

from ..errors import StippleError
from .options import (
    backend_option,
    common_options,
    init_input,
    palette_options,
    render_settings,
    resolve_input,
    warn_beyond,
)
from .recipes import colour_recipe, given_count_hint, run_pipeline, torus_recipe


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
@backend_option()
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
    "(the 0.5th and 99.5th percentiles, or the extremes where those would clip a spot): a faint document's strokes "
    "get the full range (docs/picture.md).",
)
@palette_options(None)
@click.pass_context
def torus(ctx, image, **options):
    """Stipple IMAGE (PNG, JPEG, TIFF, ..., or a .npy map; '-' for stdin) on the torus; with --palette, one
    layer of dots per ink (as 'stipple colour')."""
    from ..colour import check_palette_extras

    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    try:
        check_palette_extras(options["palette"], options["black"], options["union_weight"])
        if options["n_points"] == "auto" and options["dot_radius"] is not None:
            # The count is the pen's smallest dots' (docs/plotters.md); dots of a fixed size overlapped in thousands.
            raise StippleError("-M auto counts the pen's smallest dots; with --dot-radius give the number of dots")
        if options["palette"] is not None:
            from ..pipelines.colour import stipple_colour

            if options["n_points"] == "auto":
                raise StippleError("-M auto is for one ink (stipple torus without --palette)")
            return run_pipeline(stipple_colour, image, colour_recipe(options), options, [("image", image)], started)
        from ..pipelines.image import stipple_image

        recipe = torus_recipe(options)
        inputs = [("image", image), init_input(options["init"])]
        hints = {
            "inspect": lambda weights: (
                tone_hints(weights, options),
                peak_hint(weights, options),
                init_outside(weights.shape, options),
            ),
            "chosen": lambda count: report_count(count, options),
        }
        run_pipeline(stipple_image, image, recipe, options, inputs, started, **hints)
    except StippleError as error:
        raise click.ClickException(str(error)) from None


def init_outside(shape, options):
    """A warning when ``--init``'s points (a CSV in pixels) lie outside the image, as ``stipple render`` gives: a
    start made for another image (5000 points of a 300 x 200 run, 1764 outside a 200 x 200 image) wraps around."""
    from ..pipelines.inputs import INITS, read_points

    if options["quiet"] or options["init"] in INITS:
        return
    domain, pixels = read_points(options["init"])
    if domain == "torus":  # otherwise refused with the run's own reading
        warn_beyond(pixels, shape, options, "the start wraps them around")


def report_count(count, options):
    """``-M auto``'s choice on stderr: the count and why, a note when the darkest tones are out of reach, and the
    numbers behind it with ``-v`` (unless ``--quiet``)."""
    if options["quiet"]:
        return
    lines = [line for line in (count.reason(), count.note()) if line]
    for line in lines + ([count.details()] if options["verbose"] else []):
        click.echo(f"stipple: {line}", err=True)


# A note when the input's peak raises the bandwidth this many times over an even input's with the same dots.
PEAK_NOTE = 2.0


def peak_hint(weights, options):
    """A note when a dark peak raises the default bandwidth (``stipple.torus.default_bandwidth``) to resolve its
    dots: a small dark spot on a white 600 x 400 page took 62 s and 2.2 GB for 10000 dots, against seconds for a
    photo, without a word (a held-out review)."""
    import numpy as np

    count = options["n_points"]  # checked where it entered (``checked_count``), or "auto"
    if options["quiet"] or options["bandwidth"] is not None or count == "auto":
        return
    if np.any(weights > 0):  # a blank image is refused by the run itself (its peak ratio divides by zero)
        from ..pipelines.pen import placement_density
        from ..torus import default_bandwidth

        placed = placement_density(weights, count, render_settings(options))  # a pen's clipping, as the run's
        peak_note(default_bandwidth(count, np.ones(weights.shape)), default_bandwidth(count, placed), options)


def peak_note(even, peaked, options, what="image's darkest part", mark="a small dark mark on a light page"):
    """The note of ``peak_hint`` (and ``stipple sphere``'s) where ``peaked`` is ``PEAK_NOTE`` times ``even``."""
    if not options["quiet"] and peaked >= PEAK_NOTE * even:
        click.echo(
            f"stipple: note: the {what} packs its dots far closer than the rest ({mark}): the bandwidth rises "
            f"from {even} to {peaked} to resolve them, and the run takes longer and more memory than an even "
            "input's (docs/defaults.md, N at a peak)",
            err=True,
        )


# Hints on stderr, never a silent change: a faint document (its gray values span less than this) and a mostly
# dark image (mean darkness above this) are drawn as they are, with the option that would help named.
FAINT_SPAN, DARK_MEAN = 0.6, 0.75


def tone_hints(weights, options):
    """One line each for a faint or a mostly dark input, unless --quiet, --levels or --invert was given, and for
    tones that the plotter style cannot reach (unless --quiet; -M auto says it itself)."""
    if options["quiet"]:
        return

    from ..io.levels import faint_span

    given_count_hint(weights, options)
    if options["levels"] is not None or options["invert"]:
        return

    # A page of one gray with small marks or a soft spot, and a plain gray with noise, have nothing for --levels
    # auto (``faint_span``); a dark photo gets the hint below instead (stretched, its few highlights went white and
    # the rest lighter).
    dark = weights.mean() > DARK_MEAN
    span = None if dark else faint_span(weights, FAINT_SPAN)
    if span is not None:
        click.echo(
            f"stipple: note: the image's gray values span only {span:.0%} of the range; drawn as they are "
            "(--levels auto stretches them to black and white: docs/picture.md)",
            err=True,
        )
    if dark:
        # An image black all over has no light parts for --invert (it is blank under it).
        hint = (
            "--invert draws its light parts as white dots on black: docs/picture.md"
            if weights.min() < 1
            else "it is black all over"
        )
        click.echo(
            f"stipple: note: the image is {weights.mean():.0%} dark on average; drawn dark as it is ({hint})", err=True
        )
