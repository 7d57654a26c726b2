"""``stipple colour``: one class of dots per ink of a colour image, optimised jointly."""

import time

import click

from ..errors import StippleError
from .defaults import INITS
from .options import (
    backend_option,
    common_options,
    palette_options,
    resolve_input,
    without,
)
from .recipes import colour_recipe, given_count_hint, run_pipeline


@click.command()
# The inks print on white paper in their own colours, from the image's colours as they are.
@without("invert", "value_range", "gamma", "color", "background")
@click.argument("image", required=False)
@common_options
@palette_options("cmyk")
@click.option("--init", type=click.Choice(INITS), default="density", show_default=True)
@backend_option()
@click.option("--hessian", type=click.Choice(["gauss-newton", "full"]), default="gauss-newton", show_default=True)
@click.pass_context
def colour(ctx, image, **options):
    """Stipple a colour IMAGE with one layer of dots per ink (CSV x,y,layer; SVG one layer per pen)."""
    from ..colour import check_palette_extras
    from ..pipelines.colour import stipple_colour

    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    try:
        check_palette_extras(options["palette"], options["black"], options["union_weight"])
        recipe, inputs = colour_recipe(options), [("image", image)]

        def inspect(darkness):
            given_count_hint(darkness, options)

        run_pipeline(stipple_colour, image, recipe, options, inputs, started, inspect=inspect)
    except StippleError as error:
        raise click.ClickException(str(error)) from None
