"""``stipple evaluate``: how well saved points reproduce their input, as text or JSON (and a spectrum plot)."""

import json

import click

from ..errors import StippleError
from ..io.commit import commit_outputs
from ..io.png import spectrum_plot
from ..io.points import read_points
from .options import check_extension, check_longitude
from .supervise import guarded_files


@click.command()
@click.argument("points_source", metavar="POINTS")
@click.argument("input_source", metavar="INPUT", required=False)
@click.option("-N", "--bandwidth", type=int, default=None, help="Bandwidth of E_N (default: as stipple would use).")
@click.option("--uniform", is_flag=True, help="Sphere: against w ≡ 1 (no INPUT).")
@click.option("--kernel", default="distance", show_default=True, help="Sphere kernel of E_N.")
@click.option("--lon0", type=float, default=0.0, show_default=True, help="Sphere maps: first column's longitude.")
@click.option("--invert", is_flag=True, help="As for the run.")
@click.option("--gamma", type=float, default=1.0, show_default=True, help="As for the run.")
@click.option("--range", "value_range", type=(float, float), default=None, help="As for the run.")
@click.option(
    "--palette",
    default="cmyk",
    show_default=True,
    help="Layered CSVs (x,y,layer or x,y,color): the run's --palette, to separate INPUT into its inks.",
)
@click.option("--black", type=click.FloatRange(0, 1), default=1.0, show_default=True, help="As for the run (cmyk).")
@click.option("--json", "json_path", default=None, help="Also write the numbers as JSON ('-' for stdout).")
@click.option("--spectrum", "spectrum_path", default=None, help="Torus: PNG plot of the power spectrum.")
@click.option("--line", "as_line", is_flag=True, help="POINTS are the vertices of one closed line (stipple line).")
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
):
    """Measure how well POINTS (a stipple CSV) reproduce INPUT (image, map, builtin:NAME, or --uniform); layered
    CSVs per ink and for all dots together."""
    from ..reports import evaluation_report, format_report

    options = {
        "uniform": uniform,
        "invert": invert,
        "gamma": gamma,
        "value_range": value_range,
        "palette": palette,
        "black": black,
    }
    try:
        options["lon0"] = check_longitude("lon0", lon0)
        check_extension("--json", json_path, ".json")
        check_extension("--spectrum", spectrum_path, ".png")
        if json_path == "-" and spectrum_path == "-":
            raise StippleError("'-' (stdout) may be given only once")
        reports = [(role, path) for role, path in (("--json", json_path), ("--spectrum", spectrum_path)) if path]
        reports.append(("report", "-"))  # the text report, or --json -, goes to stdout: it must be open
        with guarded_files([("points", points_source), ("input", input_source)], [], reports=reports):
            domain, points, names = read_points(points_source, labels=True)
            if len(points) < 2:
                raise StippleError(f"{points_source}: evaluate needs at least 2 points, not {len(points)}")
            if spectrum_path is not None and (domain != "torus" or as_line):
                raise StippleError("--spectrum is for torus points only")
            report = evaluation_report(
                domain, points, names, input_source, bandwidth=bandwidth, kernel=kernel, as_line=as_line, **options
            )
            files = []
            if spectrum_path is not None:
                spectrum = report["spectrum"]
                plot = spectrum_plot(spectrum["frequency"], spectrum["power"], spectrum["anisotropy_db"])
                files.append((spectrum_path, plot))
            if json_path is not None:
                files.append((json_path, (json.dumps(report, indent=2) + "\n").encode()))
            if json_path != "-":
                files.append(("-", (format_report(report) + "\n").encode()))
            commit_outputs(files)
    except StippleError as error:
        raise click.ClickException(str(error)) from None
