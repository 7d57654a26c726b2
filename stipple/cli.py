"""Command-line interface: parses options, calls one library function, writes outputs.

Exit codes: 0 success, 1 bad data or a runtime problem, 2 bad usage (click's own).
"""

import io
import sys
import time

import click
import numpy as np

from . import __version__
from .errors import StippleError
from .halftone import default_threads
from .inputs import load_density
from .outputs import PROJECTIONS, check_writable, output_format, parse_length
from .transforms import BACKENDS


class Progress:
    """A tqdm bar on stderr showing energy, relative gradient norm and speed; off when quiet or not a TTY."""

    def __init__(self, total, quiet, start=0):
        self.bar = None
        if not quiet and sys.stderr.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=total, initial=start, unit="it", file=sys.stderr, dynamic_ncols=True)
        self.last = start

    def __call__(self, state):
        if self.bar is not None:
            self.bar.update(state.iteration - self.last)
            self.bar.set_postfix_str(f"E={state.energy:.4e} |g|/|g0|={state.relative_gradient_norm:.2e}", refresh=False)
        self.last = state.iteration
        return False

    def close(self):
        if self.bar is not None:
            self.bar.close()


def run_options(function):
    """Options shared by ``torus`` and ``sphere``: size, stopping, reproducibility, speed, outputs."""
    options = [
        click.option("-M", "--points", "n_points", type=int, default=30000, show_default=True, help="Number of dots."),
        click.option(
            "-N", "--bandwidth", type=int, default=None, help="Even kernel bandwidth (default: from M, see README)."
        ),
        click.option(
            "--iterations",
            type=click.IntRange(min=0),
            default=2000,
            show_default=True,
            help="Maximum number of CG iterations.",
        ),
        click.option(
            "--tol",
            type=float,
            default=1e-4,
            show_default=True,
            help="Stop at this gradient norm relative to the start.",
        ),
        click.option("--time-limit", type=float, default=None, help="Stop after this many seconds."),
        click.option("--seed", type=int, default=0, show_default=True, help="Seed of the random start."),
        click.option(
            "--threads", type=click.IntRange(min=1), default=None, help="Transform threads (default: all usable CPUs)."
        ),
        click.option(
            "--epsilon",
            type=click.FloatRange(min=1e-14, max=1e-2),
            default=None,
            help="Requested accuracy of the transforms.",
        ),
        click.option("--invert", is_flag=True, help="White dots on black: w = u instead of 1 - u."),
        click.option("--gamma", type=float, default=1.0, show_default=True, help="Apply w**gamma."),
        click.option(
            "--range",
            "value_range",
            type=(float, float),
            default=None,
            help="For .npy maps: the values sent to 0 and 1 (default: min and max).",
        ),
        click.option(
            "-o",
            "--output",
            "outputs",
            multiple=True,
            default=("-",),
            show_default=True,
            help="Output file (.csv .svg .png, sphere also .geojson); repeatable; '-' is CSV on stdout.",
        ),
        click.option("--width", default="200mm", show_default=True, help="SVG width (mm, cm, in, px)."),
        click.option("--dot-radius", default=None, help="Dot radius in SVG/PNG (default: keeps the mean tone)."),
        click.option("--png-width", type=click.IntRange(min=16, max=32768), default=None, help="PNG width in pixels."),
        click.option("-q", "--quiet", is_flag=True, help="No progress bar or summary."),
    ]
    for option in reversed(options):
        function = option(function)
    return function


def load_input(source, **options):
    """The density of ``source`` (``-`` is stdin) or a one-line error."""
    if source == "-":
        stream = io.BytesIO(sys.stdin.buffer.read())
        stream.name = "<stdin>"
        return load_density(stream, **options)
    return load_density(source, **options)


def render_settings(width, dot_radius, png_width):
    return {
        "width": parse_length(width),
        "dot_radius": None if dot_radius is None else parse_length(dot_radius),
        "png_width": png_width,
    }


def prepare_outputs(paths):
    """Check every output's format and directory before any work is done."""
    for path in paths:
        output_format(path)
        check_writable(path)
    if list(paths).count("-") > 1:
        raise StippleError("'-' (stdout) may be given only once")


def emit(path, data):
    from .outputs import atomic_write

    if path == "-":
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()
    else:
        atomic_write(path, data)


def report(result, quiet, started):
    if not quiet:
        click.echo(f"{result.message}; E={result.energy:.6e}, {time.perf_counter() - started:.1f} s", err=True)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="stipple")
def main():
    """Halftoning by discrepancy minimisation on the torus and the sphere."""


@main.command()
@click.argument("image")
@run_options
@click.option(
    "--init",
    default="density",
    show_default=True,
    help="Start: 'density' (i.i.d. from the image), 'uniform', or a CSV of x,y pixel positions.",
)
@click.option("--backend", type=click.Choice(BACKENDS), default="ducc0", show_default=True, help="NUFFT library.")
@click.option(
    "--hessian",
    type=click.Choice(["gauss-newton", "full"]),
    default="gauss-newton",
    show_default=True,
    help="Hessian of the Newton step and Daniel's beta.",
)
def torus(
    image,
    n_points,
    bandwidth,
    iterations,
    tol,
    time_limit,
    seed,
    threads,
    epsilon,
    invert,
    gamma,
    value_range,
    outputs,
    width,
    dot_radius,
    png_width,
    quiet,
    init,
    backend,
    hessian,
):
    """Stipple IMAGE (PNG, JPEG, TIFF, or a .npy map; '-' for stdin) on the torus."""
    from .outputs import torus_output
    from .torus import DEFAULT_EPSILON, halftone_torus

    started = time.perf_counter()
    try:
        settings = render_settings(width, dot_radius, png_width)
        prepare_outputs(outputs)
        weights = load_input(image, invert=invert, gamma=gamma, value_range=value_range)
        start = read_torus_init(init, weights.shape)
        progress = Progress(iterations, quiet)
        try:
            result = halftone_torus(
                weights,
                n_points,
                bandwidth,
                init=start,
                seed=seed,
                tol=tol,
                iterations=iterations,
                time_limit=time_limit,
                backend=backend,
                threads=threads or default_threads(),
                epsilon=epsilon or DEFAULT_EPSILON,
                hessian=hessian,
                callback=progress,
            )
        finally:
            progress.close()
        for path in outputs:
            emit(path, torus_output(result.points, weights.shape, output_format(path), ink=weights.mean(), **settings))
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    report(result, quiet, started)


def read_torus_init(init, shape):
    """``density``/``uniform``, or a CSV ``x,y`` in pixel units converted to unit coordinates."""
    if init in ("density", "uniform"):
        return init
    from .inputs import read_points_csv

    pixels = read_points_csv(init, ("x", "y"))
    rows, columns = shape
    return np.mod(pixels / np.array([columns, rows]), 1.0)


@main.command()
@click.argument("map_source", metavar="MAP", required=False)
@run_options
@click.option("--uniform", is_flag=True, help="w ≡ 1 (numerical spherical designs); no MAP.")
@click.option(
    "--lon0",
    type=float,
    default=0.0,
    show_default=True,
    help="Longitude (degrees east) where the map's first column starts (-180 for maps centred on 0°).",
)
@click.option("--kernel", default="distance", show_default=True, help="'distance' (the paper's) or 'sobolev:S'.")
@click.option(
    "--init",
    default="density",
    show_default=True,
    help="Start: 'density', 'uniform', or a CSV of lon,lat (degrees) or x,y,z.",
)
@click.option(
    "--coords", type=click.Choice(["lonlat", "xyz"]), default="lonlat", show_default=True, help="CSV columns."
)
@click.option(
    "--projection",
    type=click.Choice(PROJECTIONS),
    default="ortho",
    show_default=True,
    help="PNG view: orthographic globe or equirectangular map.",
)
@click.option("--view", default="0,0", show_default=True, help="Centre LON,LAT of the globe view (degrees).")
def sphere(
    map_source,
    n_points,
    bandwidth,
    iterations,
    tol,
    time_limit,
    seed,
    threads,
    epsilon,
    invert,
    gamma,
    value_range,
    outputs,
    width,
    dot_radius,
    png_width,
    quiet,
    uniform,
    lon0,
    kernel,
    init,
    coords,
    projection,
    view,
):
    """Stipple MAP on the sphere: an equirectangular .npy map (rescaled to [0, 1]), an image (w = 1 - u),
    'builtin:gaussians' or 'builtin:rbf' (the paper's Figs. 5.4 and 5.5), or --uniform."""
    from .outputs import sphere_output
    from .sphere import DEFAULT_EPSILON, halftone_sphere, lon_lat

    started = time.perf_counter()
    try:
        settings = render_settings(width, dot_radius, png_width)
        view_angles = parse_view(view)
        prepare_outputs(outputs)
        density = load_sphere_density(
            map_source, uniform, invert=invert, gamma=gamma, value_range=value_range, lon0=lon0
        )
        progress = Progress(iterations, quiet)
        try:
            result = halftone_sphere(
                density,
                n_points,
                bandwidth,
                kernel=kernel,
                init=read_sphere_init(init),
                seed=seed,
                tol=tol,
                iterations=iterations,
                time_limit=time_limit,
                threads=threads or default_threads(),
                epsilon=epsilon or DEFAULT_EPSILON,
                callback=progress,
            )
        finally:
            progress.close()
        degrees = lon_lat(result.points)
        for path in outputs:
            emit(
                path,
                sphere_output(
                    result.points,
                    degrees,
                    output_format(path),
                    coords=coords,
                    projection=projection,
                    view=view_angles,
                    ink=density.mean,
                    **settings,
                ),
            )
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    report(result, quiet, started)


def parse_view(text):
    try:
        lon, lat = (float(part) for part in text.split(","))
    except ValueError:
        raise StippleError(f"view must be LON,LAT in degrees, not {text!r}") from None
    if not -90 <= lat <= 90:
        raise StippleError(f"view latitude must be in [-90, 90], not {lat}")
    return lon, lat


def load_sphere_density(source, uniform, lon0, **options):
    """The density object of MAP, a built-in name, or w ≡ 1."""
    from .sphere import BUILTINS, CellMap

    if uniform:
        if source is not None:
            raise StippleError("give either MAP or --uniform, not both")
        return BUILTINS["uniform"]
    if source is None:
        raise StippleError("missing MAP (a .npy map, an image, builtin:NAME) or --uniform")
    if source.startswith("builtin:"):
        name = source.partition(":")[2]
        if name not in BUILTINS:
            raise StippleError(f"unknown built-in density {name!r}; choose from {', '.join(BUILTINS)}")
        return BUILTINS[name]
    return CellMap(load_input(source, **options), lon0)


def read_sphere_init(init):
    """``density``/``uniform``, or a CSV of ``lon,lat`` degrees or ``x,y,z`` as unit vectors."""
    if init in ("density", "uniform"):
        return init
    from .inputs import read_points_csv
    from .sphere import from_lon_lat

    try:
        longitude, latitude = read_points_csv(init, ("lon", "lat")).T
        return from_lon_lat(longitude, latitude)
    except StippleError as error:
        if "expected CSV columns" not in str(error):
            raise
    return read_points_csv(init, ("x", "y", "z"))
