"""vpype plug-ins: ``vpype stipple IMAGE ... write out.svg`` puts one layer of pen paths per ink in the document;
``vpype stippleline IMAGE ...`` one layer holding the image drawn as one closed line (``stipple line``). The second
is not called ``line``: vpype's own ``line X0 Y0 X1 Y1`` draws a segment, and a plug-in of that name would
replace it.

Installed with ``pip install 'stipple[plotter]'`` (vpype registers it through the ``vpype.plugins`` entry
point). Lengths follow vpype's conventions (``200mm``, ``8in``; bare numbers are CSS pixels); layers get the
ink's name, colour and the pen width, so ``vpype ... write`` and the AxiDraw software see one pen per layer.
"""

from functools import partial

import click
import numpy as np
import vpype as vp
import vpype_cli

from .colour import check_palette_extras, halftone_colour, palette_number, parse_palette
from .errors import StippleError
from .halftone import check_count
from .io.units import INTEGER, MAX_LENGTH_MM, MIN_LENGTH_MM
from .line import LINE_ITERATIONS
from .multiclass import class_slices
from .pipelines.colour import ink_layers
from .pipelines.pen import placement_density
from .progressive import order_dots, progressive_colour
from .render.dots import flat_dots, left_out_note
from .render.pen import dot_paths
from .render.styles import DOT_STYLES, check_dot_radius_style


def pen_layers(
    image, n_points, *, width, separation="gray", dot_style="circle", pen_width, dot_radius=None, order=None, **options
):
    """``(name, colour, paths)`` per ink, the page height, in the document's units (CSS pixels), and the number
    of dots left out where they would touch.

    ``separation`` is a ``--palette`` value (``stipple.colour.parse_palette``); ``options`` go to
    ``stipple.colour.halftone_colour``. The default dot radius keeps the image's tone (the dots of all inks
    together cover the union density's mean share of the page), capped at 0.45 × each dot's distance to its
    nearest dot, dots too close for the pen's smallest dot left out (no two dots touch), and every dot lies
    inside the image (``stipple.render.dots.flat_dots``). ``order`` "path" draws
    each layer along one short pen path, "progressive" in passes, each layer's own (``stipple.progressive``).
    """
    palette = parse_palette(separation)
    draw = {"dot_style": dot_style, "dot_radius": dot_radius, "style": "plotter", "width": (width, "px")}
    placement = partial(placement_density, n_points=n_points, draw={**draw, "pen_width": (pen_width, "px")})
    if order == "progressive":
        layers, result, counts = progressive_colour(image, n_points, separation=palette, placement=placement, **options)
        parts = class_slices([sum(passes) for passes in counts])
        inks = [(layer.name, layer.colour, result.points[part]) for layer, part in zip(layers, parts, strict=True)]
        ink = sum(layer.density for layer in layers).mean()
    else:
        layers, problem, result = halftone_colour(image, n_points, separation=palette, placement=placement, **options)
        inks, ink = ink_layers(layers, problem, result)
        counts = [None] * len(inks)
    rows, columns = layers[0].density.shape
    scale = width / columns
    tone = scale * np.sqrt(ink * rows * columns / (np.pi * n_points))
    placed = [(name, colour, points * np.array([columns, rows]) * scale) for name, colour, points in inks]
    size = (width, rows * scale)
    dots = flat_dots(placed, size, tone_radius=tone, radius=dot_radius, pen=pen_width, dot_style=dot_style)
    dots = [order_dots(d, order, kept_passes(passes, d.kept)) for d, passes in zip(dots, counts, strict=True)]
    drawn = [(d.name, d.colour, dot_paths(d.centres, d.radii, dot_style, pen_width)) for d in dots]
    return drawn, rows * scale, sum(len(points) for _, _, points in placed) - sum(len(d.centres) for d in dots)


def kept_passes(counts, kept):
    """Dots per pass (``counts``, or None) of the dots ``kept`` (a mask of the layer's, or None for all); a pass
    whose dots were all left out is dropped (an ink's smallest passes have one dot each)."""
    if counts is None or kept is None:
        return counts
    ends = np.cumsum(counts)
    passes = [int(kept[end - count : end].sum()) for count, end in zip(counts, ends, strict=True)]
    return [count for count in passes if count > 0]


@click.command("stipple")
@click.argument("image", type=click.Path(exists=True, dir_okay=False))
@click.option(
    "-M",
    "--points",
    "n_points",
    default="10000",
    show_default=True,
    help="Number of dots, or 'auto': from --pen-width, --dot-style and --width (stipple's docs/plotters.md).",
)
@click.option(
    "--palette",
    "--separation",
    "separation",
    default="gray",
    show_default=True,
    help="Inks: cmyk, cmy, gray, or pen colours '#00a0e0,#e0007a,...'.",
)
@click.option("--black", type=click.FloatRange(0, 1), default=1.0, show_default=True, help="Grey into black (cmyk).")
@click.option("--union-weight", type=float, default=1.0, show_default=True, help="Weight of the all-dots term.")
@click.option("-w", "--width", type=vpype_cli.LengthType(), default="200mm", show_default=True, help="Image width.")
@click.option("--dot-style", type=click.Choice(DOT_STYLES), default="circle", show_default=True)
@click.option("--pen-width", type=vpype_cli.LengthType(), default="0.3mm", show_default=True)
@click.option("--dot-radius", type=vpype_cli.LengthType(), default=None, help="Default: keeps the image's tone.")
@click.option("--iterations", type=vpype_cli.IntegerType(), default=2000, show_default=True)
@click.option("--tol", type=float, default=1e-4, show_default=True)
@click.option("--seed", type=vpype_cli.IntegerType(), default=0, show_default=True)
@click.option(
    "--order",
    type=click.Choice(["path", "progressive"]),
    default=None,
    help="Each layer along one short pen path, or in passes whose every prefix is an even stipple of its ink.",
)
@vpype_cli.global_processor
def stipple(document, image, n_points, width, pen_width, dot_radius, **options):
    """Stipple IMAGE into one new layer per ink (the image's top-left corner at the origin)."""
    try:
        check_lengths(width=width, pen_width=pen_width, dot_radius=dot_radius, seed=options["seed"])
        check_dot_radius_style(options["dot_style"], dot_radius)
        check_palette_extras(options["separation"], options["black"], options["union_weight"])
        n_points = plugin_count(n_points, image, width, pen_width, options)
        drawn, height, left_out = pen_layers(
            image, n_points, width=width, pen_width=pen_width, dot_radius=dot_radius, **options
        )
        if left_out:
            click.echo(f"stipple: note: {left_out_note(left_out, f'{n_points} dots')}", err=True)
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    separation = parse_palette(options["separation"])
    for name, colour, paths in drawn:
        layer_id = plugin_layer_id(document, palette_number(separation, name))
        document.add(vp.LineCollection(paths), layer_id)
        layer = document.layers[layer_id]
        layer.set_property(vp.METADATA_FIELD_NAME, name)
        layer.set_property(vp.METADATA_FIELD_COLOR, vp.Color(*(int(round(255 * c)) for c in colour)))
        layer.set_property(vp.METADATA_FIELD_PEN_WIDTH, pen_width)
    document.extend_page_size((width, height))
    return document


stipple.help_group = "Plugins"


def plugin_layer_id(document, number):
    """The layer id of the palette's ink ``number`` (1, 2, ...): that number where the document has no such layer
    yet, so that an ink keeps its pen's slot where an earlier ink got no dots (as ``stipple colour``'s SVG), else
    the document's next free id."""
    return number if number not in document.layers else document.free_id()


CSS_PIXEL_MM = 25.4 / 96


def check_lengths(seed, **lengths):
    """Refuse, in one line, a length outside stipple's own range, 1 µm to 1 km (None: not given), and a negative
    seed, as stipple's commands do (the plug-in drew ``stroke-width="-3.78"``, a page 1e299 cm wide, or raised from
    deep inside for a pen 1e300 mm wide)."""
    for name, value in lengths.items():
        if value is not None and not (np.isfinite(value) and MIN_LENGTH_MM <= value * CSS_PIXEL_MM <= MAX_LENGTH_MM):
            raise StippleError(
                f"--{name.replace('_', '-')} must be a length from {MIN_LENGTH_MM:g}mm to {MAX_LENGTH_MM:g}mm, "
                f"not {value * CSS_PIXEL_MM:g}mm"
            )
    if not 0 <= seed < 2**63:
        raise StippleError(f"--seed must be an integer in [0, 2^63), not {seed!r}")


def plugin_count(text, image, width, pen_width, options):
    """``-M``: a whole number, or ``auto`` from the pen and the page (``stipple.render.pen_count``; the choice on
    stderr)."""
    from .render.pen_count import auto_count, ink_darkness

    if str(text).strip().lower() != "auto":
        if not INTEGER.fullmatch(str(text)):
            raise StippleError(f"-M must be a whole number or 'auto', not {text!r}")
        count = int(text)
        return check_count(count)  # before the pen's density divides by it (-M 0: a numpy warning, then the error)
    darkness = ink_darkness(image, parse_palette(options["separation"]), options["black"])
    count = auto_count(darkness, width * CSS_PIXEL_MM, options["dot_style"], pen_width * CSS_PIXEL_MM)
    for line in (count.reason(), count.note()):
        if line:
            click.echo(f"stipple: {line}", err=True)
    return count.n_points


def line_path(image, n_vertices, *, width, pen_width=0.0, length=None, invert=False, **options):
    """The closed line through ``image`` as complex vertices in CSS pixels (closed: the first repeated last), at
    least half of ``pen_width`` from the page's edges as ``stipple line`` draws it (``within``), and the page
    height; ``options`` go to ``stipple.line.draw_line``."""
    from .io.images import load_density
    from .line import draw_line, line_points
    from .render.flat import within

    weights = load_density(image, invert=invert)
    rows, columns = weights.shape
    height = rows * width / columns
    result = draw_line(weights, n_vertices, length, **options)
    pixels = within(line_points(result.points) * np.array([width, height]), (width, height), pen_width / 2)
    path = pixels[:, 0] + 1j * pixels[:, 1]
    return np.append(path, path[:1]), height


@click.command("stippleline")
@click.argument("image", type=click.Path(exists=True, dir_okay=False))
@click.option("-M", "--vertices", "n_vertices", type=vpype_cli.IntegerType(), default=10000, show_default=True)
@click.option("--length", type=float, default=None, help="Line length in input pixels (default: from M and image).")
@click.option("-w", "--width", type=vpype_cli.LengthType(), default="200mm", show_default=True, help="Image width.")
@click.option("--pen-width", type=vpype_cli.LengthType(), default="0.3mm", show_default=True)
@click.option("--invert", is_flag=True, help="Draw the light parts (a light drawing on dark paper).")
@click.option("--iterations", type=vpype_cli.IntegerType(), default=LINE_ITERATIONS, show_default=True)
@click.option("--seed", type=vpype_cli.IntegerType(), default=0, show_default=True)
@vpype_cli.global_processor
def stippleline(document, image, n_vertices, width, pen_width, **options):
    """Draw IMAGE as one closed line in one new layer (the image's top-left corner at the origin)."""
    try:
        check_lengths(width=width, pen_width=pen_width, seed=options["seed"])
        path, height = line_path(image, n_vertices, width=width, pen_width=pen_width, **options)
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    layer_id = document.free_id()
    document.add(vp.LineCollection([path]), layer_id)
    layer = document.layers[layer_id]
    layer.set_property(vp.METADATA_FIELD_NAME, "line")
    layer.set_property(vp.METADATA_FIELD_COLOR, vp.Color(0, 0, 0))
    layer.set_property(vp.METADATA_FIELD_PEN_WIDTH, pen_width)
    document.extend_page_size((width, height))
    return document


stippleline.help_group = "Plugins"
