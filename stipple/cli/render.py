"""``stipple render``: saved points drawn again (SVG, PNG, CSV, GeoJSON) without rerunning the optimiser."""

import click

from ..errors import StippleError
from ..io.commit import output_format
from ..render.styles import PROJECTIONS
from .options import look_options, parse_levels, render_settings, warn_beyond
from .supervise import guarded_files, plot_order, write_outputs
from .values import FiniteFloatRange, IntegerRange, Number, some_output
from .views import check_view_drawn, parse_view


@click.command()
@click.argument("points_source", metavar="POINTS")
@click.option(
    "-o",
    "--output",
    "outputs",
    multiple=True,
    default=("-",),
    show_default=True,
    callback=some_output,
    help="Output (.csv .svg .png .geojson); repeatable; '-' is CSV on stdout.",
)
@click.option(
    "--like",
    default=None,
    help="Torus: the input image, for its size and the tone the dots draw (without it: plotter-style dots, 50 % ink).",
)
@click.option("--size", default=None, help="Torus: WIDTH,HEIGHT of the input in pixels (default: from the points).")
@click.option("--width", default="200mm", show_default=True, help="SVG width (mm, cm, in, pt, px).")
@click.option("--dot-radius", default=None, help="Dot radius in SVG/PNG, e.g. 0.3mm.")
@click.option("--png-width", type=IntegerRange(min=16, max=32768), default=None, help="PNG width in pixels.")
@click.option("--order", is_flag=True, help="Order the dots along a short pen path (pen plotters).")
@click.option(
    "--coords", type=click.Choice(["lonlat", "xyz"]), default="lonlat", show_default=True, help="Sphere CSV columns."
)
@click.option(
    "--projection", type=click.Choice(PROJECTIONS), default="ortho", show_default=True, help="Sphere PNG view."
)
@click.option(
    "--view",
    default="0,0",
    show_default=True,
    help="Centre LON,LAT of the globe view (equirect: the map's centre longitude).",
)
@click.option("--invert", is_flag=True, help="Draw white dots on black.")
@click.option("--gamma", type=Number(), default=None, help="One ink's points with --like: the run's --gamma.")
@click.option("--levels", default=None, help="One ink's points with --like: the run's --levels (auto or BLACK,WHITE).")
@click.option(
    "--range",
    "value_range",
    type=(Number(), Number()),
    default=None,
    help="One ink's points with --like: the run's --range.",
)
@click.option(
    "--palette",
    default=None,
    help="Layered points (a CSV with a layer column, as stipple colour writes): the palette of --like's separation "
    "(default: the inks the layers are named by; pens named by colour in the order they appear).",
)
@click.option(
    "--black",
    type=FiniteFloatRange(0, 1),
    default=None,
    help="Layered points with --like: the run's --black (cmyk; default 1).",
)
@look_options
@click.option("-q", "--quiet", is_flag=True, help="No log lines.")
def render(
    points_source, outputs, like, size, coords, projection, view, palette, black, gamma, levels, value_range, **options
):
    """Render saved POINTS (a stipple CSV; '-' for stdin) without rerunning the optimiser."""
    import numpy as np

    from ..io.png import check_png_outputs
    from ..pipelines.inputs import read_points, torus_canvas
    from ..pipelines.outputs import sphere_files, torus_files
    from ..pipelines.pen import placement_density
    from ..render.dots import sphere_canvas, sphere_png_layers
    from ..render.pen import physical_centres
    from ..sphere import lon_lat

    png_width = options["png_width"]
    try:
        settings = render_settings(options)
        angles = parse_view(view, projection)
        formats = [output_format(path) for path in outputs]
        if like is not None and size is not None:
            raise StippleError("give --like or --size, not both (--like's image has its own size)")
        run_transfer = [
            ("--gamma", "gamma", gamma),
            ("--levels", "levels", parse_levels(levels)),
            ("--range", "value_range", value_range),
        ]
        given = [name for name, _, value in run_transfer if value is not None]
        transfer = {key: value for name, key, value in run_transfer if name in given}
        if given and like is None:
            raise StippleError(
                f"{', '.join(given)}: for the tone of --like's image; without --like they would be ignored"
            )
        with guarded_files([("points", points_source), ("--like image", like)], outputs):
            domain, points, names = read_points(points_source, labels=True)
            if names is not None:
                if given:
                    raise StippleError(
                        f"{', '.join(given)}: for one ink's points (a colour run's are drawn from its inks)"
                    )
                files = redraw(points, names, formats, like, size, (palette, black), options)
                write_outputs(outputs, files, options["quiet"])
                return
            if palette is not None or black is not None:
                raise StippleError("--palette and --black are for layered points (a CSV with a layer column)")
            if domain == "sphere":
                if like is not None or size is not None or given:
                    raise StippleError(
                        "--like and --size are for torus points (an image's x,y); sphere points are drawn with "
                        "even dots: for a map's tone, give stipple sphere the outputs"
                    )
                check_view_drawn(click.get_current_context(), formats)
                layers = sphere_png_layers(projection, (settings["color"], settings["background"]))
                check_png_outputs(formats, sphere_canvas(projection), png_width, len(points), layers)
                points = plot_order(points, points, options, "radians")
                degrees = lon_lat(points)
                files = sphere_files(
                    points, degrees, formats, coords=coords, projection=projection, view=angles, **settings
                )
                write_outputs(outputs, files, options["quiet"])
                return
            check_view_drawn(click.get_current_context(), formats, drawn=False)
            shape, darkness, wrapped = torus_canvas(points, like, size, {"invert": options["invert"], **transfer})
            if darkness is not None:  # the ink a pen's dots carry, as the run drew them
                darkness = placement_density(darkness, len(points), settings)
            check_png_outputs(formats, shape[::-1], png_width, len(points))
            if like is not None or size is not None:
                warn_beyond(points, shape, options, "drawn wrapped onto it")
            points = wrapped
            unit = points / np.array([shape[1], shape[0]])
            unit = plot_order(physical_centres(unit, shape, settings["width"]), unit, options, settings["width"][1])
            write_outputs(outputs, torus_files(unit, shape, formats, settings, darkness), options["quiet"])
    except StippleError as error:
        raise click.ClickException(str(error)) from None


def redraw(pixels, names, formats, like, size, separation, options):
    """The files of layered torus points (``stipple.pipelines.colour.redraw_layers``); ``separation`` is
    ``(--palette, --black)``, for the tone of ``like``'s inks."""
    from ..colour import parse_palette
    from ..io.images import load_colour
    from ..pipelines.colour import redraw_layers
    from ..pipelines.inputs import torus_canvas

    if options["invert"] or options.get("color") is not None or options.get("background") is not None:
        raise StippleError("--invert, --color and --background are for one-colour dots; inks print on white paper")
    palette, black = separation
    if like is None and (palette is not None or black is not None):
        raise StippleError("--palette and --black separate --like's image: give --like, the colour image of the points")
    draw = render_settings(options)
    draw.pop("color")
    like = None if like is None else load_colour(like)
    # ``redraw_layers`` wraps the points onto the canvas: only ``torus_canvas``'s canvas is needed.
    shape = like.shape[:2] if like is not None else torus_canvas(pixels, None, size)[0]
    palette = None if palette is None else parse_palette(palette)
    black = 1.0 if black is None else black
    order = options["order"]
    files = redraw_layers(
        pixels, names, formats, draw, like=like, shape=shape, palette=palette, black=black, order=order
    )
    if like is not None or size is not None:
        warn_beyond(pixels, shape, options, "drawn wrapped onto it")
    return files
