"""Option groups shared by the commands, and the conversions of their values (lengths, colours, views)."""

import os

import click

from ..errors import MissingInput, StippleError
from ..io.sources import EMPTY_NAME
from ..io.units import parse_number
from ..render.styles import DOT_STYLES, STYLES, check_dot_radius_style
from .config import load_config
from .defaults import BACKENDS, BETAS, DEFAULT_SETTLE, INITS, ORDERS, SETTLE_WINDOW
from .values import FiniteFloatRange, Integer, IntegerRange, Number, checked_count, some_output


def click_error(error):
    """The click exception that reports a library error in one line: a missing input is bad usage (exit code 2, as
    a missing argument), any other error exit code 1."""
    return (click.UsageError if isinstance(error, MissingInput) else click.ClickException)(str(error))


def resolve_input(ctx, given):
    """The IMAGE/MAP argument, or ``input`` from the config file."""
    return given if given is not None else (ctx.default_map or {}).get("input")


def config_option():
    return click.option(
        "--config",
        type=click.Path(dir_okay=False),
        callback=load_config,
        is_eager=True,
        expose_value=False,
        help="TOML file of option values (command-line options win).",
    )


def backend_option():
    """The transforms' library, shared by the commands on the torus."""
    return click.option(
        "--backend",
        type=click.Choice(BACKENDS),
        default="ducc0",
        show_default=True,
        help="NUFFT library (cufinufft: an NVIDIA GPU, pip install 'stipple[gpu]').",
    )


# ``stipple line`` runs in phases of a growing penalty: its --iterations is the first phase's cap.
PHASED_ITERATIONS = "CG iterations of the first phase at most; each later phase gets a quarter as many (at least 1)."


def run_options(iterations=2000, iterations_help="Maximum total number of CG iterations."):
    """Stopping, reproducibility and speed: shared by every optimising command."""
    return [
        click.option(
            "--iterations",
            type=IntegerRange(min=0),
            default=iterations,
            show_default=True,
            help=iterations_help,
        ),
        click.option(
            "--time-limit",
            type=FiniteFloatRange(min=0, min_open=True),
            default=None,
            help="Stop optimising after this many seconds (reading the input, the set-up and the outputs come on top).",
        ),
        click.option("--seed", type=Integer(), default=0, show_default=True, help="Seed of the random start."),
        click.option(
            "--threads",
            type=Integer(),
            default=None,
            help="Transform threads (default: all CPUs; the same thread count gives the same points).",
        ),
        click.option("--epsilon", type=Number(), default=None, help="Requested accuracy of the transforms."),
        click.option(
            "--beta",
            type=click.Choice(BETAS),
            default="hestenes-stiefel",
            show_default=True,
            help="CG direction rule: Hestenes-Stiefel (one Jacobian transform per iteration) or the paper's "
            "Daniel (two).",
        ),
    ]


def output_options():
    """Output files and the drawing of dots."""
    return [
        click.option(
            "-o",
            "--output",
            "outputs",
            multiple=True,
            default=("-",),
            show_default=True,
            callback=some_output,
            help="Output (.csv .svg .png; sphere also .geojson); repeatable; '-' is CSV on stdout.",
        ),
        click.option("--width", default="200mm", show_default=True, help="SVG width (mm, cm, in, pt, px)."),
        click.option("--dot-radius", default=None, help="Dot radius in SVG/PNG, e.g. 0.3mm (default: keeps the tone)."),
        click.option("--png-width", type=IntegerRange(min=16, max=32768), default=None, help="PNG width in pixels."),
        click.option(
            "--order",
            type=click.Choice(ORDERS),
            is_flag=False,
            flag_value="path",
            default=None,
            help="Order the dots for a pen plotter: a bare --order (or 'path') along one short pen path; 'progressive' "
            "(stipple torus, one ink): in passes, every prefix an even stipple of the whole image (docs/plotters.md).",
        ),
        look_options,
    ]


def session_options():
    """Checkpoints and what is reported."""
    return [
        click.option(
            "--checkpoint",
            type=click.Path(dir_okay=False),
            default=None,
            help="Save the optimiser state here (atomically) during and after the run.",
        ),
        click.option(
            "--checkpoint-every",
            default="60s",
            show_default=True,
            help="Checkpoint interval: seconds (60s, 5m) or iterations (100).",
        ),
        click.option("--resume", is_flag=True, help="Continue the run saved in --checkpoint."),
        click.option("-q", "--quiet", is_flag=True, help="No progress bar or summary."),
        click.option("-v", "--verbose", is_flag=True, help="Also report the settings chosen."),
    ]


def apply_options(function, options):
    for option in reversed(options):
        function = option(function)
    return function


class CountOrAuto(Integer):
    """``-M``: a whole number, or ``auto`` (the count from the pen: ``stipple.render.pen_count``)."""

    name = "integer|auto"
    words = "a whole number in decimal digits or 'auto'"

    def convert(self, value, param, ctx):
        if isinstance(value, str) and value.strip().lower() == "auto":
            return "auto"
        return super().convert(value, param, ctx)


def common_options(function=None, *, iterations=2000, settle=True, auto_count=False, phased=False):
    """Options shared by ``torus``, ``sphere``, ``line`` and ``colour``: size, stopping, reproducibility, speed,
    the density's transfer, files and outputs. ``@common_options(iterations=K)`` changes the default cap;
    ``settle=False`` leaves out ``--settle`` (for commands whose runs stop otherwise); ``auto_count=True``
    lets ``-M`` be ``auto``; ``phased=True`` says what ``--iterations`` caps in phased runs (``stipple line``)."""
    if function is None:
        return lambda function: common_options(
            function, iterations=iterations, settle=settle, auto_count=auto_count, phased=phased
        )
    count_help = (
        "Number of dots, or 'auto': from --pen-width, --dot-style and --width (docs/plotters.md)."
        if auto_count
        else "Number of dots."
    )
    problem = [
        click.option(
            "-M",
            "--points",
            "n_points",
            type=CountOrAuto() if auto_count else Integer(),
            callback=checked_count,
            default=30000,
            show_default=True,
            help=count_help,
        ),
        click.option(
            "-N", "--bandwidth", type=Integer(), default=None, help="Kernel bandwidth (default: from M; README)."
        ),
        click.option(
            "--tol",
            type=Number(),
            default=1e-4,
            show_default=True,
            help="Stop when the gradient norm falls to this fraction of the initial one (for the torus's stratified "
            "start: of the one at i.i.d. density samples; sphere --uniform, whose kernel has a design term: 1e-6 "
            "unless given).",
        ),
        click.option("--safeguard", is_flag=True, help="Halve CG steps that would raise the energy."),
        click.option(
            "--near-field/--no-near-field",
            default=None,
            help="Sum the kernel's short range over neighbouring pairs: the untruncated discrepancy, no clumps "
            "(default; sphere: with the distance kernel). --no-near-field: the paper's bandlimited E_N.",
        ),
        click.option(
            "--invert",
            is_flag=True,
            help="Dots on the light parts (images: w = u; maps: w = 1 - map), drawn white on black.",
        ),
        click.option("--gamma", type=Number(), default=1.0, show_default=True, help="Use w**gamma."),
        click.option(
            "--range",
            "value_range",
            type=(Number(), Number()),
            default=None,
            help="For .npy maps: the values sent to 0 and 1 (default: min and max).",
        ),
    ]
    if settle:
        problem.append(
            click.option(
                "--settle",
                type=FiniteFloatRange(min=0),
                default=None,
                help=f"Also stop when the last {SETTLE_WINDOW} iterations lowered the energy by less than this "
                f"fraction of it (default: {DEFAULT_SETTLE:g} for one ink on the torus and for sphere maps, 1.5e-3 "
                "for a progressive order; 1e-12, a stalled run, for uniform points and sphere runs without the "
                "near field's distance kernel; else never; README, Defaults).",
            )
        )
    runs = run_options(iterations, PHASED_ITERATIONS) if phased else run_options(iterations)
    return apply_options(function, [config_option()] + problem + runs + output_options() + session_options())


def without(*names):
    """Leave out the options ``names`` (parameter names) that the groups below it added: they would not act on
    the command. Placed right under ``@click.command()``, so that it sees every option of the command."""

    def decorate(function):
        function.__click_params__ = [param for param in function.__click_params__ if param.name not in names]
        return function

    return decorate


def look_options(function):
    """Options of the drawing (SVG and PNG) shared by every command that draws dots."""
    options = [
        click.option(
            "--background",
            default=None,
            help="Paper colour of SVG/PNG: #rrggbb, #rgb or a name (default white; black with --invert).",
        ),
        click.option(
            "--color",
            default=None,
            help="Dot colour of SVG/PNG (default black; white with --invert).",
        ),
        click.option(
            "--dot-style",
            type=click.Choice(("disc",) + DOT_STYLES),
            default="disc",
            show_default=True,
            help="SVG/PNG dots: filled discs, or pen paths (outline, spiral fill, point) for plotters; the PNG then "
            "previews the pen strokes.",
        ),
        click.option("--pen-width", default="0.3mm", show_default=True, help="Pen stroke width of the pen styles."),
        click.option(
            "--style",
            type=click.Choice(STYLES),
            default=None,
            help="tone: each dot sized so that the drawn ink has the input's tone, darks included (dots may "
            "overlap; the default for filled discs). plotter: one tone radius capped so that no two dots touch "
            "(its darkest about 42 % gray), drawing inset; the default for the pen dot styles.",
        ),
    ]
    for option in reversed(options):
        function = option(function)
    return function


def palette_options(default):
    """``--palette``, ``--black`` and ``--union-weight``: colour separation into one class of dots per ink."""

    def decorate(function):
        options = [
            click.option(
                "--palette",
                "--separation",
                "palette",
                default=default,
                show_default=default is not None,
                help="Inks: cmyk, cmy, gray (one black ink), or pen colours '#00a0e0,#e0007a,#ffe000,#000000' "
                "(separated by non-negative least squares; README). One layer of dots per ink, optimised jointly.",
            ),
            click.option(
                "--black",
                type=FiniteFloatRange(0, 1),
                default=1.0,
                show_default=True,
                help="Fraction of the grey component min(c, m, y) printed in black (cmyk).",
            ),
            click.option(
                "--union-weight",
                type=Number(),
                default=1.0,
                show_default=True,
                help="Weight of the all-dots term against each ink's own (0: inks optimised apart).",
            ),
        ]
        for option in reversed(options):
            function = option(function)
        return function

    return decorate


def render_settings(options):
    """The drawing settings of the command's options: lengths parsed, colours resolved (``--invert``: white dots
    on black unless ``--background`` / ``--color`` say otherwise)."""
    from ..io.units import BLACK, WHITE, parse_colour, parse_length

    invert = bool(options.get("invert"))
    background, color = options.get("background"), options.get("color")
    # None: not given; an empty text is refused by parse_colour (it meant the default without a word: a sweep)
    background = parse_colour(background, "background") if background is not None else (BLACK if invert else WHITE)
    color = parse_colour(color, "color") if color is not None else (WHITE if invert else BLACK)
    if color == background:  # --invert --background white drew white dots on white: a blank picture
        raise StippleError(
            f"the dots (--color{', white under --invert' if invert and not options.get('color') else ''}) and the "
            "--background are the same colour: nothing would show"
        )
    return {
        "width": parse_length(options["width"], "width"),
        "dot_radius": dot_radius(options),
        "png_width": options["png_width"],
        "background": background,
        "color": color,
        "dot_style": options["dot_style"],
        "pen_width": parse_length(options["pen_width"], "pen-width"),
        "style": drawing_style(options.get("style"), options["dot_style"]),
    }


def parse_levels(text):
    """``--levels``: None, "auto" or ``(black, white)`` from "BLACK,WHITE" (range checked by the loader)."""
    if text is None or text == "auto":
        return text
    try:
        black, white = (parse_number(part) for part in text.split(","))
    except ValueError:
        raise StippleError(f"--levels must be 'auto' or BLACK,WHITE (two numbers in [0, 1]), not {text!r}") from None
    return black, white


def drawing_style(style, dot_style):
    """``--style``, by default "tone" for filled discs and "plotter" for the pen dot styles."""
    if style is None:
        return "tone" if dot_style == "disc" else "plotter"
    if style == "tone" and dot_style != "disc":
        raise StippleError(f"--style tone draws filled discs; --dot-style {dot_style} is for --style plotter")
    return style


def is_default(ctx, name):
    """Whether option ``name`` kept its default (not given on the command line, in the environment or a config)."""
    return ctx.get_parameter_source(name) is click.core.ParameterSource.DEFAULT


def given_on_command_line(ctx, name):
    """Whether option ``name`` was given on the command line (not by default, the environment or a config file);
    False without a context."""
    return ctx is not None and ctx.get_parameter_source(name) is click.core.ParameterSource.COMMANDLINE


def init_input(init, starts=INITS):
    """The ``--init`` value as an input file role, or None for one of ``starts``; refused, naming both readings, where
    it is neither a start nor an existing file (``--init stratifed`` said only that the file did not exist)."""
    if init in starts:
        return None
    if init == "":
        raise StippleError(f"--init: {EMPTY_NAME}")
    if str(init) != "-" and not os.path.exists(init):
        raise StippleError(f"--init: {init!r} is neither a start ({', '.join(starts)}) nor an existing file")
    return ("--init file", init)


def check_extension(option, path, extension):
    """Refuse a report file whose name does not end in ``extension`` (``-`` is stdout)."""
    if path not in (None, "-") and not str(path).lower().endswith(extension):
        raise StippleError(f"{path}: {option} writes {extension} files; the name must end in {extension}")


def warn_beyond(pixels, shape, options, consequence):
    """``warn_outside`` for pixel positions and the ``shape = (H, W)`` image they are used with (``stipple render``'s
    ``--like`` or ``--size``, ``stipple torus``'s ``--init``), unless ``--quiet``."""
    from ..measures.reports import outside

    if not options["quiet"]:
        found = outside(pixels, shape)
        warn_outside(found["points_outside"], len(pixels), found["image_size"], consequence)


def warn_outside(count, total, size, consequence):
    """A warning on stderr when ``count`` of ``total`` points lie outside the ``size = (W, H)`` image they are used
    with (points made for another image, which the torus wraps around), ending with ``consequence``."""
    if count:
        columns, rows = size
        click.echo(
            f"stipple: warning: {count} of {total} points lie outside the {columns}×{rows} image "
            f"(made for another image?); {consequence}",
            err=True,
        )


def dot_radius(options):
    """``--dot-radius`` parsed, at most half the drawing's ``--width`` (a radius of 1 km drew for minutes), or None."""
    from ..io.units import UNITS, parse_length

    if options["dot_radius"] is None:
        return None
    check_dot_radius_style(options.get("dot_style"), options["dot_radius"])
    radius, width = parse_length(options["dot_radius"], "dot-radius"), parse_length(options["width"], "width")
    if radius[0] * UNITS[radius[1]] > 0.5 * width[0] * UNITS[width[1]]:
        raise StippleError(
            f"--dot-radius {options['dot_radius']} is more than half the drawing's --width {options['width']}"
        )
    return radius
