"""``stipple line``: an image drawn as one closed line."""

import time

import click

from ..errors import StippleError
from .defaults import LINE_ITERATIONS
from .options import common_options, resolve_input, without
from .supervise import finish, guarded_files, supervised, write_outputs
from .values import Number

# How the line's settings are spelt in messages: the options typed.
OPTION_NAMES = {"length": "--length", "bandwidth": "-N/--bandwidth"}


@click.command()
@click.option(
    "--pen-width",
    default=None,
    help="Stroke width of the line, e.g. 0.3mm (default: the tone-true stroke, whose ink covers the image's mean "
    "darkness; docs/line.md).",
)
# The line is drawn with one pen, black on white (--invert: white on black): the dot options and the dots' near
# field would do nothing.
@without("near_field", "safeguard", "dot_radius", "order", "background", "color", "dot_style", "style", "pen_width")
@click.argument("image", required=False)
@common_options(iterations=LINE_ITERATIONS, settle=False, phased=True)
@click.option(
    "--length",
    type=Number(),
    default=None,
    help="Curve length in pixels (default: c sqrt(M W H), c 0.6-1.1 from M/(W H); docs/line.md).",
)
@click.option("--init", default=None, help="Start: a CSV of x,y pixel positions in path order (default: a loop).")
@click.pass_context
def line(ctx, image, **options):
    """Draw IMAGE as one closed line (-M vertices) whose length measure minimises the discrepancy."""
    from ..halftone import check_count
    from ..io.commit import FLAT_FORMATS, output_format
    from ..io.images import load_input
    from ..io.png import check_png_outputs
    from ..io.units import BLACK, WHITE, parse_length
    from ..line import line_points
    from ..line.problem import line_settings
    from ..pipelines.outputs import line_files
    from ..render.flat import line_png_width

    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    try:
        width = parse_length(options["width"])
        pen_width = None if options["pen_width"] is None else parse_length(options["pen_width"], "pen-width")
        inputs = [("image", image)] + ([] if options["init"] is None else [("--init file", options["init"])])
        with guarded_files(inputs, options["outputs"], options["checkpoint"], formats=FLAT_FORMATS):
            weights = load_input(
                image, invert=options["invert"], gamma=options["gamma"], value_range=options["value_range"]
            )
            check_count(options["n_points"])
            line_settings(weights, options["n_points"], options["length"], options["bandwidth"], OPTION_NAMES)
            formats = [output_format(path) for path in options["outputs"]]
            png_width = line_png_width(options["png_width"], weights.shape)
            check_png_outputs(formats, weights.shape[::-1], png_width, options["n_points"])
            init = None if options["init"] is None else read_line_init(options["init"], weights.shape, options)
            result, stopped_by = solve_line(weights, options, init)
            points = line_points(result.points)
            colours = {"color": WHITE, "background": BLACK} if options["invert"] else {}
            files = line_files(
                points,
                weights.shape,
                formats,
                width=width,
                pen_width=pen_width,
                png_width=png_width,
                ink=float(weights.mean()),
                **colours,
            )
            write_outputs(options["outputs"], files, options["quiet"])
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)


def read_line_init(source, shape, options):
    """``--init``'s vertices (a CSV ``x,y`` in pixels, path order) in unit coordinates: exactly ``-M`` of them,
    inside the image."""
    import numpy as np

    from ..pipelines.inputs import read_points

    domain, pixels = read_points(source)
    rows, columns = shape
    if domain != "torus":
        raise StippleError(f"--init {source}: the line's start needs a CSV with columns x,y (pixels)")
    if len(pixels) != options["n_points"]:
        raise StippleError(
            f"--init {source}: {len(pixels)} vertices, but -M is {options['n_points']}: give one row per vertex "
            "(-M of them, in path order)"
        )
    if np.any(pixels < 0) or np.any(pixels > [columns, rows]):
        raise StippleError(f"--init {source}: vertices must lie in the image, 0..{columns} by 0..{rows} pixels")
    return pixels / np.array([columns, rows])


def solve_line(weights, options, init):
    """``draw_line`` with the CLI's stopping, checkpoint, progress and signal options."""
    from ..line import draw_line
    from ..torus import DEFAULT_EPSILON

    result, stopped_by = supervised(
        options,
        lambda keywords: draw_line(
            weights,
            options["n_points"],
            options["length"],
            options["bandwidth"],
            init=init,
            threads=options["threads"],
            epsilon=DEFAULT_EPSILON if options["epsilon"] is None else options["epsilon"],
            **keywords,
        ),
    )
    if options["verbose"] and not options["quiet"]:
        segments = result.segment_lengths
        click.echo(
            f"stipple: line N={result.bandwidth}, length {segments.sum():.1f} px, penalty {result.penalty:g}, "
            f"max/mean segment {segments.max() / segments.mean():.4f}",
            err=True,
        )
    return result, stopped_by
