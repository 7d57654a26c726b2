"""``stipple evaluate``: how well saved points, or a drawn PNG, reproduce their input, as text or JSON (and a
spectrum plot)."""

import json
import os

import click

from ..errors import MissingInput, StippleError
from ..io.commit import commit_outputs
from ..io.sources import PICTURE_EXTENSIONS
from .defaults import DEFAULT_LIFT, DEFAULT_SPEED, DEFAULT_TRAVEL_SPEED, MAX_POINTS
from .options import check_extension, click_error, given_on_command_line, parse_levels, warn_outside
from .supervise import guarded_files
from .values import FiniteFloatRange, Integer, IntegerRange, Number
from .views import check_longitude


@click.command()
@click.argument("points_source", metavar="POINTS")
@click.argument("input_source", metavar="INPUT", required=False)
@click.option(
    "-N", "--bandwidth", type=Integer(), default=None, help="Bandwidth of E_N (default: as stipple would use)."
)
@click.option("--uniform", is_flag=True, help="Sphere: against w ≡ 1 (no INPUT).")
@click.option("--kernel", default="distance", show_default=True, help="Sphere kernel of E_N.")
@click.option("--lon0", type=Number(), default=0.0, show_default=True, help="Sphere maps: first column's longitude.")
@click.option("--invert", is_flag=True, help="As for the run.")
@click.option("--gamma", type=Number(), default=1.0, show_default=True, help="As for the run.")
@click.option("--range", "value_range", type=(Number(), Number()), default=None, help="As for the run.")
@click.option(
    "--palette",
    default="cmyk",
    show_default=True,
    help="Layered CSVs (x,y,layer or x,y,color): the run's --palette, to separate INPUT into its inks.",
)
@click.option("--black", type=FiniteFloatRange(0, 1), default=1.0, show_default=True, help="As for the run (cmyk).")
@click.option("--json", "json_path", default=None, help="Also write the numbers as JSON ('-' for stdout).")
@click.option("--spectrum", "spectrum_path", default=None, help="Torus: PNG plot of the power spectrum.")
@click.option("--line", "as_line", is_flag=True, help="POINTS are the vertices of one closed line (stipple line).")
@click.option(
    "--sigma",
    "sigmas",
    type=FiniteFloatRange(min=0, min_open=True),
    multiple=True,
    help="Pictures: blur in input pixels, repeatable (default 2 and 4).",
)
@click.option(
    "--colour/--gray",
    "--color/--grey",
    "colour",
    default=None,
    help="Pictures: CIELAB or luminance measures (default: CIELAB when INPUT has colour).",
)
@click.option("--levels", default=None, help="As for the run (auto or BLACK,WHITE).")
@click.option("--inset", type=Number(), default=0.0, show_default=True, help="Pictures: undo a drawing's inset (px).")
@click.option(
    "--floyd-steinberg",
    "fs_dots",
    type=IntegerRange(min=1, max=MAX_POINTS),
    default=None,
    help="Pictures: also measure Floyd-Steinberg error diffusion with about this many dots.",
)
@click.option("--speed", type=Number(), default=DEFAULT_SPEED, show_default=True, help="Drawings: pen-down mm/s.")
@click.option(
    "--travel-speed", type=Number(), default=DEFAULT_TRAVEL_SPEED, show_default=True, help="Drawings: pen-up mm/s."
)
@click.option("--lift", type=Number(), default=DEFAULT_LIFT, show_default=True, help="Drawings: seconds per pen lift.")
@click.option(
    "--acceleration",
    type=Number(),
    default=None,
    help="Drawings: mm/s² of every move from rest to rest (default: none).",
)
def evaluate(
    points_source,
    input_source,
    bandwidth,
    uniform,
    kernel,
    lon0,
    invert,
    gamma,
    value_range,
    palette,
    black,
    json_path,
    spectrum_path,
    as_line,
    sigmas,
    colour,
    levels,
    inset,
    fs_dots,
    **plotter,
):
    """Measure how well POINTS (a stipple CSV) reproduce INPUT (image, map, builtin:NAME, or --uniform); layered
    CSVs per ink and for all dots together. Given a drawn PICTURE (PNG, JPEG, TIFF, ...) instead of POINTS: its
    measures against INPUT, both blurred at viewing distance (luminance RMSE and tone curve, or CIEDE2000 and
    chroma).
    Given a DRAWING.svg (stipple's or vpype's): the plot's estimate per pen (paths, pen-down length, pen-up
    travel, lifts, time; docs/plotters.md)."""
    from ..measures.reports import evaluation_report
    from ..pipelines.inputs import read_points

    options = {
        "uniform": uniform,
        "invert": invert,
        "gamma": gamma,
        "value_range": value_range,
        "palette": palette,
        "black": black,
    }
    kind = source_kind(points_source)
    refuse_foreign_options(kind)
    if kind == "drawing":
        evaluate_plot(points_source, input_source, json_path, plotter)
        return
    separation_given = palette != "cmyk" or black != 1.0
    if kind == "picture":
        if separation_given:
            raise click.ClickException("--palette and --black are for layered CSVs (points), not for a drawn PICTURE")
        picture = {"sigmas": sigmas, "colour": colour, "levels": levels, "inset": inset, "fs_dots": fs_dots}
        evaluate_picture(
            points_source, input_source, json_path, picture, options, spectrum_path or bandwidth or as_line
        )
        return
    try:
        check_picture_options_absent(sigmas, colour, inset, fs_dots)
        options["levels"] = parse_levels(levels)
        check_builtin(input_source)
        options["lon0"] = check_longitude("lon0", lon0)
        check_extension("--json", json_path, ".json")
        check_extension("--spectrum", spectrum_path, ".png")
        if json_path == "-" and spectrum_path == "-":
            raise StippleError("'-' (stdout) may be given only once")
        reports = [(role, path) for role, path in (("--json", json_path), ("--spectrum", spectrum_path)) if path]
        reports.append(("report", "-"))  # the text report, or --json -, goes to stdout: it must be open
        with guarded_files([("points", points_source), ("input", input_source)], [], reports=reports):
            domain, points, names = read_points(points_source, labels=True)
            if names is None and separation_given:
                raise StippleError(f"{points_source}: --palette and --black are for layered CSVs (one ink here)")
            check_transfer_applies(points_source, domain, names, {**options, "kernel": kernel != "distance"})
            if len(points) < 2:
                raise StippleError(f"{points_source}: evaluate needs at least 2 points, not {len(points)}")
            if spectrum_path is not None and (domain != "torus" or as_line):
                raise StippleError("--spectrum is for torus points only")
            report = evaluation_report(
                domain, points, names, input_source, bandwidth=bandwidth, kernel=kernel, as_line=as_line, **options
            )
            count, size = report.get("points_outside", 0), report.get("image_size")
            warn_outside(count, report["points"], size, "the measures wrap them around")
            warn_unjudged(report, input_source)
            commit_outputs(report_files(report, json_path, spectrum_path))
    except StippleError as error:
        raise click_error(error) from None


def report_files(report, json_path, spectrum_path):
    """``(path, bytes)`` of the points' report: the spectrum's plot, the JSON, and the text on stdout (unless the
    JSON or the plot goes there: a PNG followed by text was no PNG)."""
    from ..io.png import spectrum_plot
    from ..measures.reports import format_report

    files = []
    if spectrum_path is not None:
        spectrum = report["spectrum"]
        files.append(
            (spectrum_path, spectrum_plot(spectrum["frequency"], spectrum["power"], spectrum["anisotropy_db"]))
        )
    if json_path is not None:
        files.append((json_path, (json.dumps(report, indent=2) + "\n").encode()))
    if "-" not in (json_path, spectrum_path):
        files.append(("-", (format_report(report) + "\n").encode()))
    return files


# What each kind of POINTS is measured with: a drawing's plot estimate, a picture's measures, points' measures.
PLOTTER_OPTIONS = {"speed", "travel_speed", "lift", "acceleration"}
PICTURE_OPTIONS = {"sigmas", "colour", "levels", "inset", "fs_dots", "invert", "gamma", "value_range", "palette"}
APPLIES = {
    "drawing": {"points_source", "input_source", "json_path", *PLOTTER_OPTIONS},
    "picture": {
        "points_source",
        "input_source",
        "json_path",
        *PICTURE_OPTIONS,
        "black",
        "spectrum_path",
        "bandwidth",
        "as_line",
    },
}
KINDS = {"drawing": "a DRAWING.svg's plot estimate", "picture": "a drawn PICTURE", "points": "points"}


def source_kind(points_source):
    """What ``stipple evaluate`` measures in ``points_source``: a plotter's drawing (SVG), a drawn picture (a raster
    image), or points (a CSV, or stdin)."""
    suffix = os.path.splitext(str(points_source).lower())[1]
    return "drawing" if suffix == ".svg" else "picture" if suffix in PICTURE_EXTENSIONS else "points"


def refuse_foreign_options(kind):
    """Refuse, in one line, the options given on the command line that ``kind`` of POINTS does not use: they were
    silently ignored (``evaluate d.svg --sigma 2``, ``evaluate p.csv in.png --speed 1``). The options with
    messages of their own (a picture's for points, --bandwidth for pictures, ...) are left to them."""
    context = click.get_current_context()
    applies = APPLIES.get(kind, set(context.params) - PLOTTER_OPTIONS)
    given = [name for name in context.params if name not in applies and given_on_command_line(context, name)]
    if given:
        flags = [_flag(context, name) for name in given]
        raise click.ClickException(f"{', '.join(flags)}: not for {KINDS[kind]}; it would be ignored")


def _flag(context, name):
    """The option ``name`` as given: a boolean flag's off switch (``--gray``) when it is off, else its first name."""
    (option,) = [param for param in context.command.params if param.name == name]
    if option.secondary_opts and context.params[name] is False:
        return option.secondary_opts[0]
    return option.opts[0]


def check_builtin(input_source):
    """Refuse an unknown ``builtin:NAME``, naming the built-in densities (rather than "no such file")."""
    if input_source is None or not str(input_source).startswith("builtin:"):
        return
    from ..sphere import BUILTINS

    name = str(input_source).partition(":")[2]
    if name not in BUILTINS:
        raise StippleError(f"unknown builtin {name!r}: choose from {', '.join('builtin:' + b for b in BUILTINS)}")


def check_transfer_applies(points_source, domain, names, options):
    """Refuse the density's transfer options where they would be ignored: a layered CSV is measured against the
    colour image's inks (none of them apply), sphere maps have no --levels."""
    from ..io.images import given_transfer

    given = given_transfer(options)
    if names is not None:
        if given:
            raise StippleError(f"{points_source}: {', '.join(given)}: not for layered CSVs (measured by their inks)")
    elif domain == "sphere" and "--levels" in given:
        raise StippleError(f"{points_source}: --levels is for images, not for sphere points")
    sphere_only = {"--uniform": options["uniform"], "--lon0": options["lon0"] != 0.0, "--kernel": options["kernel"]}
    named = [name for name, present in sphere_only.items() if present]
    if domain != "sphere" and named:
        raise StippleError(f"{points_source}: {', '.join(named)}: for sphere points, not for an image's")


def warn_unjudged(report, input_source):
    """A warning when fewer than half of a map's points lie where it is dark enough to judge their spacing (points
    made for another map, or another --lon0): the nearest-neighbour line was then empty, without a word."""
    judged = report.get("neighbour_points_judged")
    if report.get("domain") == "sphere" and input_source is not None and judged is not None:
        if judged < 0.5 * report["points"]:
            click.echo(
                f"stipple: warning: only {judged} of {report['points']} points lie where {input_source} has ink "
                "(made for another map, or with another --lon0?)",
                err=True,
            )


# A picture whose chroma is below this fraction of its colour input's is gray (a torus stipple of a colour photo).
GRAY_PICTURE_CHROMA = 0.05


def note_gray_picture(report, picture_source):
    """A note when a gray picture is measured against a colour input in colour (the default there): CIEDE2000
    then counts the whole missing colour (a gray stipple of a colour photo: 21.9, its luminance 2-3 times closer
    than Floyd-Steinberg's in 8 colours, which measured 1.3)."""
    ratios = [row["chroma_ratio"] for row in report.get("stipple", []) if row.get("chroma_ratio") is not None]
    if report.get("measures") == "colour" and ratios and max(ratios) < GRAY_PICTURE_CHROMA:
        click.echo(
            f"stipple: note: {picture_source} is gray and its input in colour: CIEDE2000 counts the missing colour; "
            "--gray compares the luminance",
            err=True,
        )


def check_picture_options_absent(sigmas, colour, inset, fs_dots):
    """Refuse the options that measure a drawn picture when POINTS are given: they would be ignored."""
    given = {
        "--sigma": bool(sigmas),
        "--colour/--gray": colour is not None,
        "--inset": inset != 0,
        "--floyd-steinberg": fs_dots is not None,
    }
    named = [name for name, present in given.items() if present]
    if named:
        raise StippleError(f"{', '.join(named)}: for a drawn PICTURE, not for points")


def evaluate_picture(picture_source, input_source, json_path, picture, options, point_only):
    """``stipple evaluate PICTURE INPUT``: the picture measures as text, or JSON with ``--json``."""
    from ..measures.picture import SIGMAS
    from ..measures.reports import format_picture_report, picture_report

    try:
        if input_source is None:
            raise MissingInput("missing INPUT: a picture is measured against the image it was drawn from")
        if options["uniform"]:
            raise StippleError("a picture is measured against the INPUT it was drawn from, not --uniform")
        if point_only:
            raise StippleError("--spectrum, --bandwidth and --line are for points, not pictures")
        check_extension("--json", json_path, ".json")
        levels = parse_levels(picture["levels"])
        transfer = {"invert": options["invert"], "gamma": options["gamma"], "value_range": options["value_range"]}
        reports = [("--json", json_path)] if json_path else []
        with guarded_files([("picture", picture_source), ("input", input_source)], [], reports=reports):
            report = picture_report(
                picture_source,
                input_source,
                colour=picture["colour"],
                sigmas=picture["sigmas"] or SIGMAS,
                inset=picture["inset"],
                dots=picture["fs_dots"],
                levels=levels,
                **transfer,
            )
            if picture["colour"] is None:
                note_gray_picture(report, picture_source)
            files = [("-", (format_picture_report(report) + "\n").encode())] if json_path != "-" else []
            if json_path is not None:
                files.append((json_path, (json.dumps(report, indent=2) + "\n").encode()))
            commit_outputs(files)
    except (StippleError, ValueError) as error:
        raise click_error(error) from None


def evaluate_plot(drawing, input_source, json_path, plotter):
    """``stipple evaluate DRAWING.svg``: the plot's estimate as text, or JSON with ``--json``."""
    from ..io.plot_svg import read_pen_layers
    from ..measures.plot_estimate import PlotterSettings, format_estimate, plot_estimate

    try:
        if input_source is not None:
            raise StippleError("a drawing's plot estimate takes no INPUT")
        check_extension("--json", json_path, ".json")
        settings = PlotterSettings(**plotter)
        reports = [("--json", json_path)] if json_path else []
        with guarded_files([("drawing", drawing)], [], reports=reports):
            estimate = plot_estimate(read_pen_layers(drawing), settings)
            files = [("-", (format_estimate(estimate) + "\n").encode())] if json_path != "-" else []
            if json_path is not None:
                files.append((json_path, (json.dumps(estimate.as_dict(), indent=2) + "\n").encode()))
            commit_outputs(files)
    except StippleError as error:
        raise click.ClickException(str(error)) from None
