"""Command-line interface: parses options, builds the problem, runs it, writes outputs.

Exit codes: 0 success; 1 bad data, files or settings; 2 bad usage (click's own); 130 / 143 after
SIGINT / SIGTERM (a checkpoint and the outputs reached so far are written first).
"""

import io
import os
import re
import shlex
import signal
import sys
import time

import click
import numpy as np

from . import __version__
from .config import load_config
from .errors import StippleError
from .inputs import load_density
from .outputs import PROJECTIONS, check_writable, output_format, parse_length
from .transforms import BACKENDS


class Progress:
    """A tqdm bar on stderr (energy, relative gradient norm, speed); off when quiet or stderr is not a TTY."""

    def __init__(self, total, enabled):
        self.total = total
        self.enabled = enabled
        self.bar = None

    def __call__(self, state):
        if not self.enabled:
            return False
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, initial=state.iteration, unit="it", file=sys.stderr, dynamic_ncols=True)
        self.bar.update(state.iteration - self.bar.n)
        self.bar.set_postfix_str(f"E={state.energy:.4e} |g|/|g0|={state.relative_gradient_norm:.2e}", refresh=False)
        return False

    def close(self):
        if self.bar is not None:
            self.bar.close()


class Interruption:
    """Turns SIGINT / SIGTERM into a request to stop after the current iteration (a second one exits at once)."""

    def __init__(self):
        self.signal = None
        self._previous = {}

    def __enter__(self):
        for number in (signal.SIGINT, signal.SIGTERM):
            self._previous[number] = signal.signal(number, self._handle)
        return self

    def __exit__(self, *exc):
        for number, handler in self._previous.items():
            signal.signal(number, handler)

    def _handle(self, number, frame):
        if self.signal is not None:
            os._exit(128 + number)
        self.signal = number

    def __call__(self, state):
        return self.signal is not None


def parse_every(text):
    """``"60s"``, ``"5m"`` (seconds) or ``"100"`` / ``"100it"`` (iterations) -> (seconds, iterations)."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*(s|m|h|it)?\s*", str(text))
    if not match or float(match.group(1)) <= 0:
        raise StippleError(f"checkpoint-every must be like 60s, 5m or 100 (iterations), not {text!r}")
    value, unit = float(match.group(1)), match.group(2) or "it"
    if unit == "it":
        if value != int(value):
            raise StippleError(f"checkpoint-every must be a whole number of iterations, not {text!r}")
        return None, int(value)
    return value * {"s": 1, "m": 60, "h": 3600}[unit], None


def resolve_input(ctx, given):
    """The IMAGE/MAP argument, or ``input`` from the config file."""
    return given if given is not None else (ctx.default_map or {}).get("input")


def common_options(function):
    """Options shared by ``torus`` and ``sphere``: size, stopping, reproducibility, speed, files, outputs."""
    options = [
        click.option(
            "--config",
            type=click.Path(dir_okay=False),
            callback=load_config,
            is_eager=True,
            expose_value=False,
            help="TOML file of option values (command-line options win).",
        ),
        click.option("-M", "--points", "n_points", type=int, default=30000, show_default=True, help="Number of dots."),
        click.option("-N", "--bandwidth", type=int, default=None, help="Kernel bandwidth (default: from M; README)."),
        click.option(
            "--iterations",
            type=click.IntRange(min=0),
            default=2000,
            show_default=True,
            help="Maximum total number of CG iterations.",
        ),
        click.option(
            "--tol",
            type=float,
            default=1e-4,
            show_default=True,
            help="Stop when the gradient norm falls to this fraction of the initial one.",
        ),
        click.option("--time-limit", type=float, default=None, help="Stop after this many seconds."),
        click.option("--safeguard", is_flag=True, help="Halve CG steps that would raise the energy."),
        click.option("--seed", type=int, default=0, show_default=True, help="Seed of the random start."),
        click.option(
            "--threads",
            type=int,
            default=None,
            help="Transform threads (default: torus 1, bit-reproducible; sphere all CPUs).",
        ),
        click.option("--epsilon", type=float, default=None, help="Requested accuracy of the transforms."),
        click.option(
            "--near-field/--no-near-field",
            default=None,
            help="Sum the kernel's short range over neighbouring pairs: the untruncated discrepancy, no clumps "
            "(default; sphere: with the distance kernel). --no-near-field: the paper's bandlimited E_N.",
        ),
        click.option("--invert", is_flag=True, help="Images: w = u (white dots on black); maps: w = 1 - map."),
        click.option("--gamma", type=float, default=1.0, show_default=True, help="Use w**gamma."),
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
            help="Output (.csv .svg .png; sphere also .geojson); repeatable; '-' is CSV on stdout.",
        ),
        click.option("--width", default="200mm", show_default=True, help="SVG width (mm, cm, in, px)."),
        click.option("--dot-radius", default=None, help="Dot radius in SVG/PNG, e.g. 0.3mm (default: keeps the tone)."),
        click.option("--png-width", type=click.IntRange(min=16, max=32768), default=None, help="PNG width in pixels."),
        click.option("--order", is_flag=True, help="Order the dots along a short pen path (pen plotters)."),
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
    for option in reversed(options):
        function = option(function)
    return function


def load_input(source, **options):
    """The density of ``source`` (``-`` is stdin) as an array."""
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


def prepare_outputs(paths, checkpoint):
    """Check every output's format and directory before any work is done."""
    for path in paths:
        output_format(path)
        check_writable(path)
    if list(paths).count("-") > 1:
        raise StippleError("'-' (stdout) may be given only once")
    if checkpoint is not None:
        check_writable(checkpoint)


def write_outputs(paths, render):
    """Render every output first, then write them (atomically; ``-`` is stdout)."""
    from .outputs import atomic_write

    rendered = [(path, render(output_format(path))) for path in paths]
    for path, data in rendered:
        if path == "-":
            sys.stdout.buffer.write(data)
            sys.stdout.buffer.flush()
        else:
            atomic_write(path, data)


def solve(problem, options, init):
    """Run ``problem`` with the CLI's stopping, checkpoint, progress and signal options."""
    from .halftone import run

    seconds, iterations = parse_every(options["checkpoint_every"])
    verbose = options["verbose"] and not options["quiet"]
    if verbose:
        fourier = problem.discrepancy.fourier
        transforms = getattr(fourier, "nufft", fourier)
        details = ", ".join(f"{key}={value}" for key, value in problem.settings.items())
        click.echo(
            f"stipple: {details}, threads={transforms.threads}, epsilon={transforms.epsilon:g}, "
            f"tol={options['tol']:g}, iterations<={options['iterations']}",
            err=True,
        )
    progress = Progress(options["iterations"], not options["quiet"] and sys.stderr.isatty())
    with Interruption() as interruption:
        try:
            result = run(
                problem,
                init=init,
                seed=options["seed"],
                tol=options["tol"],
                iterations=options["iterations"],
                time_limit=options["time_limit"],
                safeguard=options["safeguard"],
                callback=lambda state: progress(state) or interruption(state),
                checkpoint=options["checkpoint"],
                checkpoint_seconds=seconds,
                checkpoint_iterations=iterations,
                resume=options["resume"],
            )
        finally:
            progress.close()
    if verbose and len(result.energies) > 1:
        rises = int(np.sum(np.diff(result.energies) > 0))
        click.echo(
            f"stipple: {result.seconds / max(result.iterations, 1) * 1000:.1f} ms per iteration, "
            f"energy {result.energies[0]:.4e} -> {result.energy:.4e} ({rises} rises)",
            err=True,
        )
    return result, interruption.signal


def finish(result, stopped_by, options, started):
    """Summary on stderr, and the exit code after a signal (130 / 143) with how to resume."""
    if stopped_by is not None:
        name = signal.Signals(stopped_by).name
        if options["checkpoint"]:
            command = shlex.join(["stipple"] + sys.argv[1:] + ([] if options["resume"] else ["--resume"]))
            hint = f"resume with: {command}"
        else:
            hint = "no --checkpoint was given, so the run cannot be resumed"
        click.echo(f"stipple: stopped by {name} at iteration {result.iterations}; outputs written; {hint}", err=True)
        sys.exit(128 + stopped_by)
    if not options["quiet"]:
        click.echo(f"stipple: {result.message}; E={result.energy:.6e}; {time.perf_counter() - started:.1f} s", err=True)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="stipple")
def main():
    """Halftoning by discrepancy minimisation on the torus (images) and the sphere (global maps)."""


@main.command()
@click.argument("image", required=False)
@common_options
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
@click.pass_context
def torus(ctx, image, **options):
    """Stipple IMAGE (PNG, JPEG, TIFF, ..., or a .npy map; '-' for stdin) on the torus."""
    from .outputs import torus_output
    from .torus import DEFAULT_EPSILON, torus_problem

    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    try:
        settings = render_settings(options["width"], options["dot_radius"], options["png_width"])
        prepare_outputs(options["outputs"], options["checkpoint"])
        weights = load_input(
            image, invert=options["invert"], gamma=options["gamma"], value_range=options["value_range"]
        )
        problem = torus_problem(
            weights,
            options["n_points"],
            options["bandwidth"],
            backend=options["backend"],
            threads=options["threads"],
            epsilon=options["epsilon"] or DEFAULT_EPSILON,
            hessian=options["hessian"],
            near_field=options["near_field"] is not False,
        )
        result, stopped_by = solve(problem, options, read_torus_init(options["init"], weights.shape))
        points = plot_order(
            physical_centres(result.points, weights.shape, settings["width"]),
            result.points,
            options,
            settings["width"][1],
        )
        write_outputs(
            options["outputs"], lambda fmt: torus_output(points, weights.shape, fmt, ink=weights.mean(), **settings)
        )
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)


@main.command()
@click.argument("image", required=False)
@common_options
@click.option("--length", type=float, default=None, help="Curve length in pixels (default: 0.5 sqrt(M W H)).")
@click.option("--pen-width", default=None, help="Stroke width in SVG/PNG, e.g. 0.3mm (default: one input pixel).")
@click.option("--init", default=None, help="Start: a CSV of x,y pixel positions in path order (default: a loop).")
@click.pass_context
def line(ctx, image, **options):
    """Draw IMAGE as one closed line (-M vertices) whose length measure minimises the discrepancy."""
    from .line import line_points
    from .outputs import line_output

    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    try:
        width = parse_length(options["width"])
        pen_width = None if options["pen_width"] is None else parse_length(options["pen_width"])
        prepare_outputs(options["outputs"], options["checkpoint"])
        weights = load_input(
            image, invert=options["invert"], gamma=options["gamma"], value_range=options["value_range"]
        )
        init = None if options["init"] is None else read_torus_init(options["init"], weights.shape)
        result, stopped_by = solve_line(weights, options, init)
        points = line_points(result.points)
        write_outputs(
            options["outputs"],
            lambda fmt: line_output(
                points, weights.shape, fmt, width=width, pen_width=pen_width, png_width=options["png_width"]
            ),
        )
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)


def solve_line(weights, options, init):
    """``draw_line`` with the CLI's stopping, checkpoint, progress and signal options."""
    from .line import draw_line

    seconds, iterations = parse_every(options["checkpoint_every"])
    progress = Progress(options["iterations"], not options["quiet"] and sys.stderr.isatty())
    with Interruption() as interruption:
        try:
            result = draw_line(
                weights,
                options["n_points"],
                options["length"],
                options["bandwidth"],
                seed=options["seed"],
                init=init,
                tol=options["tol"],
                iterations=options["iterations"],
                time_limit=options["time_limit"],
                callback=lambda state: progress(state) or interruption(state),
                checkpoint=options["checkpoint"],
                checkpoint_seconds=seconds,
                checkpoint_iterations=iterations,
                resume=options["resume"],
                threads=options["threads"],
                epsilon=options["epsilon"] or 1e-9,
            )
        finally:
            progress.close()
    if options["verbose"] and not options["quiet"]:
        segments = result.segment_lengths
        click.echo(
            f"stipple: line N={result.bandwidth}, length {segments.sum():.1f} px, penalty {result.penalty:g}, "
            f"max/mean segment {segments.max() / segments.mean():.4f}",
            err=True,
        )
    return result, interruption.signal


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
@common_options
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
@click.pass_context
def sphere(ctx, map_source, **options):
    """Stipple MAP on the sphere: an equirectangular .npy map (rescaled to [0, 1]), an image (w = 1 - u),
    'builtin:gaussians' or 'builtin:rbf' (the paper's Figs. 5.4 and 5.5), or --uniform."""
    from .outputs import sphere_output
    from .sphere import DEFAULT_EPSILON, lon_lat, sphere_problem

    started = time.perf_counter()
    map_source = resolve_input(ctx, map_source)
    try:
        settings = render_settings(options["width"], options["dot_radius"], options["png_width"])
        view = parse_view(options["view"])
        prepare_outputs(options["outputs"], options["checkpoint"])
        density = load_sphere_density(map_source, options)
        problem = sphere_problem(
            density,
            options["n_points"],
            options["bandwidth"],
            kernel=options["kernel"],
            threads=options["threads"],
            epsilon=options["epsilon"] or DEFAULT_EPSILON,
            near_field=options["near_field"],
        )
        result, stopped_by = solve(problem, options, read_sphere_init(options["init"]))
        points = plot_order(result.points, result.points, options, "radians")
        degrees = lon_lat(points)
        write_outputs(
            options["outputs"],
            lambda fmt: sphere_output(
                points,
                degrees,
                fmt,
                coords=options["coords"],
                projection=options["projection"],
                view=view,
                ink=density.mean,
                **settings,
            ),
        )
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)


def physical_centres(points, shape, width):
    """Torus points on the SVG's physical canvas (in the unit of ``width``)."""
    rows, columns = shape
    return points * np.array([columns, rows]) * (width[0] / columns)


def plot_order(centres, points, options, unit):
    """``points`` reordered along a short pen path through ``centres`` when ``--order`` is given."""
    if not options.get("order"):
        return points
    from .plotter import plotter_order

    order, before, after = plotter_order(centres)
    if not options.get("quiet"):
        click.echo(f"stipple: pen-up travel {before:.4g} -> {after:.4g} {unit}", err=True)
    return points[order]


def parse_view(text):
    try:
        lon, lat = (float(part) for part in text.split(","))
    except ValueError:
        raise StippleError(f"view must be LON,LAT in degrees, not {text!r}") from None
    if not (-90 <= lat <= 90 and np.isfinite(lon)):
        raise StippleError(f"view must be a finite longitude and a latitude in [-90, 90], not {text!r}")
    return lon, lat


def load_sphere_density(source, options):
    """The density object of MAP, a built-in name, or w ≡ 1."""
    from .sphere import BUILTINS, CellMap

    if options["uniform"]:
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
    values = load_input(source, invert=options["invert"], gamma=options["gamma"], value_range=options["value_range"])
    return CellMap(values, options["lon0"])


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


def read_points(source):
    """Points from a stipple CSV (``-`` is stdin): ``("torus", pixels)`` or ``("sphere", unit vectors)``."""
    from .inputs import read_points_csv, read_source
    from .sphere import from_lon_lat

    data = read_source(sys.stdin.buffer if source == "-" else source)
    header = data.split(b"\n", 1)[0].decode("utf-8", errors="replace").replace(" ", "").lower()

    def table(names):
        stream = io.BytesIO(data)
        stream.name = "<stdin>" if source == "-" else source
        return read_points_csv(stream, names)

    if header.startswith("x,y,z"):
        points = table(("x", "y", "z"))
        return "sphere", points / np.linalg.norm(points, axis=1, keepdims=True)
    if header.startswith("x,y"):
        return "torus", table(("x", "y"))
    if header.startswith("lon,lat"):
        longitude, latitude = table(("lon", "lat")).T
        return "sphere", from_lon_lat(longitude, latitude)
    raise StippleError(f"{source}: expected a CSV with header x,y (torus) or lon,lat / x,y,z (sphere)")


def parse_size(text):
    try:
        width, height = (int(part) for part in text.lower().replace("x", ",").split(","))
    except ValueError:
        raise StippleError(f"size must be WIDTH,HEIGHT in pixels, not {text!r}") from None
    if width < 1 or height < 1:
        raise StippleError(f"size must be positive, not {text!r}")
    return height, width


@main.command()
@click.argument("points_source", metavar="POINTS")
@click.option(
    "-o",
    "--output",
    "outputs",
    multiple=True,
    default=("-",),
    show_default=True,
    help="Output (.csv .svg .png .geojson); repeatable; '-' is CSV on stdout.",
)
@click.option("--like", default=None, help="Torus: the input image, for its size and mean tone.")
@click.option("--size", default=None, help="Torus: WIDTH,HEIGHT of the input in pixels (default: from the points).")
@click.option("--width", default="200mm", show_default=True, help="SVG width (mm, cm, in, px).")
@click.option("--dot-radius", default=None, help="Dot radius in SVG/PNG, e.g. 0.3mm.")
@click.option("--png-width", type=click.IntRange(min=16, max=32768), default=None, help="PNG width in pixels.")
@click.option("--order", is_flag=True, help="Order the dots along a short pen path (pen plotters).")
@click.option(
    "--coords", type=click.Choice(["lonlat", "xyz"]), default="lonlat", show_default=True, help="Sphere CSV columns."
)
@click.option(
    "--projection", type=click.Choice(PROJECTIONS), default="ortho", show_default=True, help="Sphere PNG view."
)
@click.option("--view", default="0,0", show_default=True, help="Centre LON,LAT of the globe view.")
@click.option("-q", "--quiet", is_flag=True, help="No log lines.")
def render(points_source, outputs, like, size, width, dot_radius, png_width, order, coords, projection, view, quiet):
    """Render saved POINTS (a stipple CSV; '-' for stdin) without rerunning the optimiser."""
    from .outputs import sphere_output, torus_output
    from .sphere import lon_lat

    options = {"order": order, "quiet": quiet}
    try:
        settings = render_settings(width, dot_radius, png_width)
        prepare_outputs(outputs, None)
        domain, points = read_points(points_source)
        if domain == "sphere":
            points = plot_order(points, points, options, "radians")
            angles, degrees = parse_view(view), lon_lat(points)
            write_outputs(
                outputs,
                lambda fmt: sphere_output(
                    points, degrees, fmt, coords=coords, projection=projection, view=angles, **settings
                ),
            )
            return
        ink = None
        if like is not None:
            weights = load_input(like)
            shape, ink = weights.shape, weights.mean()
        elif size is not None:
            shape = parse_size(size)
        else:
            shape = (int(np.ceil(points[:, 1].max(initial=1))), int(np.ceil(points[:, 0].max(initial=1))))
        unit = points / np.array([shape[1], shape[0]])
        unit = plot_order(physical_centres(unit, shape, settings["width"]), unit, options, settings["width"][1])
        write_outputs(outputs, lambda fmt: torus_output(unit, shape, fmt, ink=ink, **settings))
    except StippleError as error:
        raise click.ClickException(str(error)) from None


@main.command()
@click.argument("points_source", metavar="POINTS")
@click.argument("input_source", metavar="INPUT", required=False)
@click.option("-N", "--bandwidth", type=int, default=None, help="Bandwidth of E_N (default: as stipple would use).")
@click.option("--uniform", is_flag=True, help="Sphere: against w ≡ 1 (no INPUT).")
@click.option("--kernel", default="distance", show_default=True, help="Sphere kernel of E_N.")
@click.option("--lon0", type=float, default=0.0, show_default=True, help="Sphere maps: first column's longitude.")
@click.option("--invert", is_flag=True, help="As for the run.")
@click.option("--gamma", type=float, default=1.0, show_default=True, help="As for the run.")
@click.option("--range", "value_range", type=(float, float), default=None, help="As for the run.")
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
    json_path,
    spectrum_path,
    as_line,
):
    """Measure how well POINTS (a stipple CSV) reproduce INPUT (image, map, builtin:NAME, or --uniform)."""
    import json

    from .evaluate import evaluate_sphere, evaluate_torus
    from .outputs import spectrum_plot

    options = {"uniform": uniform, "invert": invert, "gamma": gamma, "value_range": value_range, "lon0": lon0}
    try:
        if json_path not in (None, "-"):
            check_writable(json_path)
        if spectrum_path is not None:
            check_writable(spectrum_path)
        domain, points = read_points(points_source)
        if spectrum_path is not None and (domain != "torus" or as_line):
            raise StippleError("--spectrum is for torus points only")
        if as_line:
            report = evaluate_line_points(points, domain, input_source, bandwidth, invert, gamma, value_range)
        elif domain == "torus":
            from .torus import torus_problem

            if input_source is None:
                raise StippleError("missing INPUT: the image or map the points were made from")
            weights = load_input(input_source, invert=invert, gamma=gamma, value_range=value_range)
            unit = np.mod(points / np.array([weights.shape[1], weights.shape[0]]), 1.0)
            problem = torus_problem(weights, len(points), bandwidth, epsilon=1e-10)
            report = evaluate_torus(problem, unit, weights)
        else:
            from .sphere import sphere_problem

            density = load_sphere_density(input_source, options)
            problem = sphere_problem(density, len(points), bandwidth, kernel=kernel, epsilon=1e-12)
            report = evaluate_sphere(problem, points, density)
        if spectrum_path is not None:
            spectrum = report["spectrum"]
            emit_file(spectrum_path, spectrum_plot(spectrum["frequency"], spectrum["power"], spectrum["anisotropy_db"]))
        if json_path is not None:
            emit_file(json_path, (json.dumps(report, indent=2) + "\n").encode())
        if json_path != "-":
            click.echo(format_report(report))
    except StippleError as error:
        raise click.ClickException(str(error)) from None


def evaluate_line_points(pixels, domain, input_source, bandwidth, invert, gamma, value_range):
    """The report of ``stipple evaluate --line``: E_N of the vertices, length, segments, the drawn line's PSNR."""
    from .evaluate import evaluate_line
    from .line import closed_length, line_problem

    if domain != "torus" or input_source is None:
        raise StippleError("--line needs a CSV of x,y vertices and the image they were drawn from")
    weights = load_input(input_source, invert=invert, gamma=gamma, value_range=value_range)
    problem = line_problem(weights, len(pixels), closed_length(pixels), bandwidth, epsilon=1e-10)
    return evaluate_line(problem, pixels / np.array([weights.shape[1], weights.shape[0]]), weights)


def emit_file(path, data):
    from .outputs import atomic_write

    if path == "-":
        sys.stdout.buffer.write(data)
    else:
        atomic_write(path, data)


def format_report(report):
    """The evaluation as aligned ``name: value`` lines (the spectrum only as its range)."""
    lines = [
        f"domain: {report['domain']}",
        f"points: {report['points']}",
        f"bandwidth: {report['bandwidth']}",
        f"E_N: {report['energy']:.6e}",
        f"E_N of i.i.d. samples (expected): {report['expected_iid_energy']:.6e}",
        f"ratio to i.i.d.: {report['energy_ratio_to_iid']:.4g}",
    ]
    for item in report.get("similarity", []):
        lines.append(f"blur sigma {item['sigma']:g} px: PSNR {item['psnr']:.2f} dB, SSIM {item['ssim']:.4f}")
    if "neighbour_distance_over_hexagonal" in report:
        stats = report["neighbour_distance_over_hexagonal"]
        lines.append("nearest neighbour / hexagonal spacing: " + ", ".join(f"{k} {v:.3f}" for k, v in stats.items()))
    for key in ("length_pixels", "max_over_mean_segment", "min_over_mean_segment"):
        if key in report:
            lines.append(f"{key.replace('_', ' ')}: {report[key]:.6g}")
    for key in ("max_coefficient_error", "minimum_separation_degrees", "cap_discrepancy"):
        if key in report:
            lines.append(f"{key.replace('_', ' ')}: {report[key]:.6g}")
    return "\n".join(lines)
