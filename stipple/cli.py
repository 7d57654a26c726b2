"""Command-line interface: parses options, builds the problem, runs it, writes outputs.

Exit codes: 0 success; 1 bad data, files or settings; 2 bad usage; 130 / 143 after SIGINT / SIGTERM
(during the optimisation a first signal writes the checkpoint and the outputs reached so far; any other
signal removes every temporary file and leaves every output whole or untouched). Every error is one line.
"""

import contextlib
import io
import re
import shlex
import signal
import sys
import time

import click
import numpy as np

from . import __version__
from .allocator import reuse_freed_memory
from .config import load_config
from .errors import StippleError
from .halftone import DEFAULT_SETTLE, INITS, MAX_POINTS, check_integer
from .inputs import load_density
from .line import LINE_ITERATIONS
from .optimize import BETAS, SETTLE_WINDOW
from .outputs import PROJECTIONS, check_png_outputs, check_writable, output_format, parse_length, sphere_canvas
from .plotter import DOT_STYLES
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


class Interrupted(BaseException):
    """Raised by the signal handler outside the optimiser (and on a second signal): unwinds every cleanup."""

    def __init__(self, number):
        super().__init__(number)
        self.number = number


class SignalGuard:
    """SIGINT / SIGTERM for the whole command.

    While the optimiser runs (``deferred``) the first signal only asks it to stop after the current
    iteration, so that the checkpoint and the outputs reached so far are written; any other signal
    raises ``Interrupted``, which removes temporary files and releases locks on its way out (exit 130 / 143);
    signals that arrive while it unwinds are ignored, so that the cleanup itself is never cut short.
    """

    def __init__(self):
        self.signal = None
        self.deferring = False
        self.unwinding = False
        self._previous = {}

    def __enter__(self):
        self.signal, self.deferring, self.unwinding = None, False, False
        for number in (signal.SIGINT, signal.SIGTERM):
            try:
                self._previous[number] = signal.signal(number, self._handle)
            except ValueError:  # not the main thread: leave signals alone
                break
        return self

    def __exit__(self, *exc):
        for number, handler in self._previous.items():
            signal.signal(number, handler)
        self._previous.clear()

    def _handle(self, number, frame):
        if self.deferring and self.signal is None:
            self.signal = number
            return
        if self.unwinding:  # already on the way out: let the cleanup finish
            return
        self.unwinding = True
        raise Interrupted(number)

    @contextlib.contextmanager
    def deferred(self):
        """Within the block a first signal is only recorded (see ``stop_requested``)."""
        self.deferring = True
        try:
            yield self
        finally:
            self.deferring = False

    def stop_requested(self, state):
        return self.signal is not None


SIGNALS = SignalGuard()


class StippleGroup(click.Group):
    """The ``stipple`` group: every error is one line on stderr, and signals unwind cleanly.

    Usage errors exit 2, data and file errors 1, SIGINT / SIGTERM 130 / 143.
    """

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        reuse_freed_memory()
        try:
            with SIGNALS:
                code = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.UsageError as error:
            hint = f" (see '{error.ctx.command_path} --help')" if error.ctx is not None else ""
            _error_line(f"Error: {error.format_message()}{hint}")
            sys.exit(error.exit_code)
        except click.ClickException as error:
            _error_line(f"Error: {error.format_message()}")
            sys.exit(error.exit_code)
        except click.Abort:
            _error_line("Aborted!")
            sys.exit(1)
        except MemoryError:
            _error_line("Error: out of memory")
            sys.exit(1)
        except OSError as error:
            _error_line(f"Error: {error.strerror or error}" + (f": {error.filename}" if error.filename else ""))
            sys.exit(1)
        except Interrupted as interruption:
            name = signal.Signals(interruption.number).name
            _error_line(f"stipple: stopped by {name}; outputs are whole or untouched, no temporary file left")
            sys.exit(128 + interruption.number)
        sys.exit(code if isinstance(code, int) else 0)


def _error_line(text):
    """``text`` on stderr as one line (newlines in messages folded)."""
    click.echo(" ".join(text.split("\n")), err=True)


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


def config_option():
    return click.option(
        "--config",
        type=click.Path(dir_okay=False),
        callback=load_config,
        is_eager=True,
        expose_value=False,
        help="TOML file of option values (command-line options win).",
    )


def run_options(iterations=2000):
    """Stopping, reproducibility and speed: shared by every optimising command."""
    return [
        click.option(
            "--iterations",
            type=click.IntRange(min=0),
            default=iterations,
            show_default=True,
            help="Maximum total number of CG iterations.",
        ),
        click.option("--time-limit", type=float, default=None, help="Stop after this many seconds."),
        click.option("--seed", type=int, default=0, show_default=True, help="Seed of the random start."),
        click.option(
            "--threads",
            type=int,
            default=None,
            help="Transform threads (default: all CPUs; the same thread count gives the same points).",
        ),
        click.option("--epsilon", type=float, default=None, help="Requested accuracy of the transforms."),
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
            help="Output (.csv .svg .png; sphere also .geojson); repeatable; '-' is CSV on stdout.",
        ),
        click.option("--width", default="200mm", show_default=True, help="SVG width (mm, cm, in, px)."),
        click.option("--dot-radius", default=None, help="Dot radius in SVG/PNG, e.g. 0.3mm (default: keeps the tone)."),
        click.option("--png-width", type=click.IntRange(min=16, max=32768), default=None, help="PNG width in pixels."),
        click.option("--order", is_flag=True, help="Order the dots along a short pen path (pen plotters)."),
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


def common_options(function=None, *, iterations=2000, settle=True):
    """Options shared by ``torus``, ``sphere``, ``line`` and ``colour``: size, stopping, reproducibility, speed,
    the density's transfer, files and outputs. ``@common_options(iterations=K)`` changes the default cap;
    ``settle=False`` leaves out ``--settle`` (for commands whose runs stop otherwise)."""
    if function is None:
        return lambda function: common_options(function, iterations=iterations, settle=settle)
    problem = [
        click.option("-M", "--points", "n_points", type=int, default=30000, show_default=True, help="Number of dots."),
        click.option("-N", "--bandwidth", type=int, default=None, help="Kernel bandwidth (default: from M; README)."),
        click.option(
            "--tol",
            type=float,
            default=1e-4,
            show_default=True,
            help="Stop when the gradient norm falls to this fraction of the initial one (for the torus's stratified "
            "start: of the one at i.i.d. density samples).",
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
        click.option("--gamma", type=float, default=1.0, show_default=True, help="Use w**gamma."),
        click.option(
            "--range",
            "value_range",
            type=(float, float),
            default=None,
            help="For .npy maps: the values sent to 0 and 1 (default: min and max).",
        ),
    ]
    if settle:
        problem.append(
            click.option(
                "--settle",
                type=click.FloatRange(min=0),
                default=None,
                help=f"Also stop when the last {SETTLE_WINDOW} iterations lowered the energy by less than this "
                f"fraction of it (default: {DEFAULT_SETTLE:g} for one ink on the torus, else never; README, Defaults).",
            )
        )
    runs = run_options(iterations)
    return apply_options(function, [config_option()] + problem + runs + output_options() + session_options())


def load_input(source, **options):
    """The density of ``source`` (``-`` is stdin) as an array."""
    if source == "-":
        stream = io.BytesIO(sys.stdin.buffer.read())
        stream.name = "<stdin>"
        return load_density(stream, **options)
    return load_density(source, **options)


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
                type=click.FloatRange(0, 1),
                default=1.0,
                show_default=True,
                help="Fraction of the grey component min(c, m, y) printed in black (cmyk).",
            ),
            click.option(
                "--union-weight",
                type=float,
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
    from .outputs import BLACK, WHITE, parse_colour

    invert = bool(options.get("invert"))
    background, color = options.get("background"), options.get("color")
    return {
        "width": parse_length(options["width"], "width"),
        "dot_radius": None if options["dot_radius"] is None else parse_length(options["dot_radius"], "dot-radius"),
        "png_width": options["png_width"],
        "background": parse_colour(background, "background") if background else (BLACK if invert else WHITE),
        "color": parse_colour(color, "color") if color else (WHITE if invert else BLACK),
        "dot_style": options["dot_style"],
        "pen_width": parse_length(options["pen_width"], "pen-width"),
    }


def _is_default(ctx, name):
    """Whether option ``name`` kept its default (not given on the command line, in the environment or a config)."""
    return ctx.get_parameter_source(name) is click.core.ParameterSource.DEFAULT


def check_longitude(name, value):
    """A finite longitude in [-360, 360] degrees."""
    if not -360 <= value <= 360:
        raise StippleError(f"{name} must be a longitude in [-360, 360] degrees, not {value!r}")
    return float(value)


@contextlib.contextmanager
def guarded_files(inputs, outputs, checkpoint=None, reports=()):
    """Check every file of a run before any work, then hold the checkpoint's lock for the whole run.

    ``inputs`` and ``reports`` are ``(role, path)`` pairs (files read; extra files written). Outputs'
    formats and directories are checked, no output may name an input, the checkpoint or another
    output, and ``-`` (stdout) may be given once.
    """
    from .safety import CheckpointLock, check_distinct

    for path in outputs:
        output_format(path)
        check_writable(path)
    for _, path in reports:
        check_writable(path)
    if list(outputs).count("-") > 1:
        raise StippleError("'-' (stdout) may be given only once")
    config = click.get_current_context().meta.get("stipple.config")
    inputs = [*inputs, ("config", config)]
    written = [("output", path) for path in outputs] + list(reports) + [("checkpoint", checkpoint)]
    check_distinct(inputs, written)
    if checkpoint is None:
        yield
        return
    check_writable(checkpoint)
    with CheckpointLock(checkpoint):
        yield


def init_input(init):
    """The ``--init`` value as an input file role, or None for ``density`` / ``uniform``."""
    return None if init in INITS else ("--init file", init)


def write_outputs(paths, render):
    """Render every output in memory, then write them all-or-nothing (``-`` is stdout)."""
    from .outputs import commit_outputs

    commit_outputs([(path, render(output_format(path))) for path in paths])


def solve(problem, options, init, stop=None):
    """Run ``problem`` with the CLI's stopping, checkpoint, progress and signal options (and ``stop``, a callback
    that ends the run by returning True)."""
    from .halftone import run

    verbose = options["verbose"] and not options["quiet"]

    def announce():
        fourier = problem.discrepancy.fourier
        transforms = getattr(fourier, "nufft", fourier)
        details = ", ".join(f"{key}={value}" for key, value in problem.settings.items())
        click.echo(
            f"stipple: {details}, threads={transforms.threads}, epsilon={transforms.epsilon:g}, "
            f"tol={options['tol']:g}, iterations<={options['iterations']}",
            err=True,
        )

    result, stopped_by = supervised(
        options,
        lambda keywords: run(
            problem,
            init=init,
            safeguard=options["safeguard"],
            correct=options.get("correct", False),
            settle=options.get("settle"),
            **keywords,
        ),
        stop,
        announce if verbose else None,
    )
    if verbose and len(result.energies) > 1:
        rises = int(np.sum(np.diff(result.energies) > 0))
        click.echo(
            f"stipple: {result.seconds / max(result.iterations, 1) * 1000:.1f} ms per iteration, "
            f"energy {result.energies[0]:.4e} -> {result.energy:.4e} ({rises} rises)",
            err=True,
        )
    return result, stopped_by


def supervised(options, launch, stop=None, announce=None):
    """``launch(keywords)`` under the CLI's progress bar and signal handling, where ``keywords`` are the stopping,
    seed, callback and checkpoint arguments that ``halftone.run`` and ``draw_line`` share. The callback also ends
    the run when ``stop`` returns True, and ``announce()`` reports the settings between the checks of the
    checkpoint interval and of the seed. Returns the result and the signal that stopped it (or None)."""
    seconds, iterations = parse_every(options["checkpoint_every"])
    if announce is not None:
        announce()
    check_integer("seed", options["seed"], 0, 2**63 - 1)
    progress = Progress(options["iterations"], not options["quiet"] and sys.stderr.isatty())
    with SIGNALS.deferred() as interruption:
        try:
            result = launch(
                {
                    "seed": options["seed"],
                    "tol": options["tol"],
                    "iterations": options["iterations"],
                    "time_limit": options["time_limit"],
                    "callback": lambda state: any(
                        [progress(state), interruption.stop_requested(state), bool(stop and stop(state))]
                    ),
                    "checkpoint": options["checkpoint"],
                    "checkpoint_seconds": seconds,
                    "checkpoint_iterations": iterations,
                    "resume": options["resume"],
                    "beta": options["beta"],
                }
            )
        finally:
            progress.close()
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


@click.group(cls=StippleGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="stipple")
def main():
    """Halftoning by discrepancy minimisation on the torus (images) and the sphere (global maps)."""


@main.command()
@click.argument("image", required=False)
@common_options
@click.option(
    "--init",
    default="stratified",
    show_default=True,
    help="Start: 'stratified' (the image's dots shared out along a Hilbert curve), 'density' (i.i.d. from the "
    "image), 'uniform', or a CSV of x,y pixel positions.",
)
@click.option("--backend", type=click.Choice(BACKENDS), default="ducc0", show_default=True, help="NUFFT library.")
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
@palette_options(None)
@click.pass_context
def torus(ctx, image, **options):
    """Stipple IMAGE (PNG, JPEG, TIFF, ..., or a .npy map; '-' for stdin) on the torus; with --palette, one
    layer of dots per ink (as 'stipple colour')."""
    from .outputs import torus_output
    from .torus import DEFAULT_EPSILON, torus_problem

    started = time.perf_counter()
    image = resolve_input(ctx, image)
    if image is None:
        raise click.UsageError("missing IMAGE (or 'input' in --config)")
    if options["palette"] is not None:
        from .cli_colour import run_colour

        return run_colour(image, options, started)
    try:
        settings = render_settings(options)
        inputs = [("image", image), init_input(options["init"])]
        with guarded_files([i for i in inputs if i], options["outputs"], options["checkpoint"]):
            weights = load_input(
                image, invert=options["invert"], gamma=options["gamma"], value_range=options["value_range"]
            )
            check_png_outputs(
                [output_format(path) for path in options["outputs"]],
                weights.shape[::-1],
                options["png_width"],
                options["n_points"],
            )
            problem = torus_problem(
                weights,
                options["n_points"],
                options["bandwidth"],
                backend=options["backend"],
                threads=options["threads"],
                epsilon=DEFAULT_EPSILON if options["epsilon"] is None else options["epsilon"],
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
                options["outputs"],
                lambda fmt: torus_output(points, weights.shape, fmt, ink=weights.mean(), **settings),
            )
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)


@main.command()
@click.argument("image", required=False)
@common_options(iterations=LINE_ITERATIONS, settle=False)
@click.option("--length", type=float, default=None, help="Curve length in pixels (default: 0.75 sqrt(M W H)).")
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
        # The line's own default stroke is one input pixel, unless --pen-width is given.
        pen_width = None if _is_default(ctx, "pen_width") else parse_length(options["pen_width"], "pen-width")
        inputs = [("image", image)] + ([] if options["init"] is None else [("--init file", options["init"])])
        with guarded_files(inputs, options["outputs"], options["checkpoint"]):
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
    from .torus import DEFAULT_EPSILON

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


def read_torus_init(init, shape):
    """``stratified``/``density``/``uniform``, or a CSV ``x,y`` in pixel units converted to unit coordinates."""
    if init in INITS:
        return init
    domain, pixels = read_points(init)
    if domain != "torus":
        raise StippleError(f"{init}: --init for the torus needs a CSV with columns x,y (pixels)")
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
@click.option(
    "--kernel",
    default=None,
    help="'distance' (the paper's; default for maps), 'distance+design:T' (default for --uniform: T = 0.96 sqrt(2M)) "
    "or 'sobolev:S'.",
)
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
    from .sphere import DESIGN_TOL, lon_lat, sphere_problem

    started = time.perf_counter()
    map_source = resolve_input(ctx, map_source)
    try:
        settings = render_settings(options)
        view = parse_view(options["view"])
        lon0 = check_longitude("lon0", options["lon0"])
        formats = [output_format(path) for path in options["outputs"]]
        check_png_outputs(formats, sphere_canvas(options["projection"]), options["png_width"], options["n_points"])
        inputs = [("map", map_source), init_input(options["init"])]
        with guarded_files([i for i in inputs if i], options["outputs"], options["checkpoint"]):
            density = load_sphere_density(map_source, {**options, "lon0": lon0})
            problem = sphere_problem(
                density,
                options["n_points"],
                options["bandwidth"],
                kernel=options["kernel"],
                threads=options["threads"],
                epsilon=options["epsilon"],
                near_field=options["near_field"],
            )
            if problem.settings["kernel"].startswith("distance+design") and _is_default(ctx, "tol"):
                options["tol"] = DESIGN_TOL
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
    if init in INITS:
        return init
    domain, points = read_points(init)
    if domain != "sphere":
        raise StippleError(f"{init}: --init for the sphere needs a CSV with columns lon,lat or x,y,z")
    return points


MAX_PIXEL_COORDINATE = 2**31


LABEL_COLUMNS = ("layer", "color", "colour")


def read_points(source, labels=False):
    """Points from a stipple CSV (``-`` is stdin): ``("torus", pixels)`` or ``("sphere", unit vectors)``.

    The header decides: ``x,y,z`` and ``lon,lat`` are sphere points (latitudes in [-90, 90], no zero
    vectors), ``x,y`` torus points in pixels (finite, below ``MAX_PIXEL_COORDINATE`` in size). With
    ``labels``, also each torus point's layer (a ``layer`` or ``color`` column, as ``stipple colour`` writes),
    or None: ``(domain, points, names)``.
    """
    from .inputs import read_points_csv, read_source
    from .sphere import from_lon_lat

    name = "<stdin>" if source == "-" else source
    data = read_source(sys.stdin.buffer if source == "-" else source)
    first_line = data.split(b"\n", 1)[0].decode("utf-8-sig", errors="replace")
    columns = {column.strip().lower() for column in first_line.split(",")}

    def table(names):
        stream = io.BytesIO(data)
        stream.name = name
        points = read_points_csv(stream, names)
        if len(points) > MAX_POINTS:
            raise StippleError(f"{name}: {len(points)} points; at most {MAX_POINTS} are read")
        return points

    if {"x", "y", "z"} <= columns:
        found = "sphere", unit_rows(table(("x", "y", "z")), name)
        return (*found, None) if labels else found
    if {"lon", "lat"} <= columns:
        longitude, latitude = table(("lon", "lat")).T
        if np.any(np.abs(latitude) > 90):
            raise StippleError(f"{name}: latitudes must lie in [-90, 90] degrees, not up to {np.abs(latitude).max():g}")
        found = "sphere", from_lon_lat(longitude, latitude)
        return (*found, None) if labels else found
    if {"x", "y"} <= columns:
        pixels = table(("x", "y"))
        if np.abs(pixels).max() >= MAX_PIXEL_COORDINATE:
            raise StippleError(
                f"{name}: x,y must be pixel positions below {MAX_PIXEL_COORDINATE} in size, "
                f"not {np.abs(pixels).max():g}"
            )
        if not labels:
            return "torus", pixels
        return "torus", pixels, read_labels(data, columns, len(pixels), name)
    raise StippleError(f"{name}: expected a CSV with header x,y (torus) or lon,lat / x,y,z (sphere)")


def read_labels(data, columns, count, name):
    """Each row's layer name from the ``layer`` / ``color`` column of CSV ``data``, or None without one."""
    column = next((label for label in LABEL_COLUMNS if label in columns), None)
    if column is None:
        return None
    lines = [line.strip() for line in data.decode("utf-8-sig").splitlines() if line.strip()]
    index = [cell.strip().lower() for cell in lines[0].split(",")].index(column)
    names = [line.split(",")[index].strip() for line in lines[1:]]
    if len(names) != count or not all(names):
        raise StippleError(f"{name}: every row needs a {column} name")
    return np.array(names)


def unit_rows(vectors, name):
    """Rows scaled to unit length (safely for tiny and huge entries); zero rows are refused."""
    largest = np.abs(vectors).max(axis=1, keepdims=True)
    if np.any(largest == 0):
        row = int(np.argmax(largest[:, 0] == 0)) + 1
        raise StippleError(f"{name}: point {row} is the zero vector (0,0,0); x,y,z must be directions")
    scaled = vectors / largest
    return scaled / np.linalg.norm(scaled, axis=1, keepdims=True)


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
@click.option("--invert", is_flag=True, help="Draw white dots on black.")
@look_options
@click.option("-q", "--quiet", is_flag=True, help="No log lines.")
def render(points_source, outputs, like, size, coords, projection, view, **options):
    """Render saved POINTS (a stipple CSV; '-' for stdin) without rerunning the optimiser."""
    from .outputs import sphere_output, torus_output
    from .sphere import lon_lat

    png_width = options["png_width"]
    try:
        settings = render_settings(options)
        angles = parse_view(view)
        formats = [output_format(path) for path in outputs]
        with guarded_files([("points", points_source), ("--like image", like)], outputs):
            domain, points = read_points(points_source)
            if domain == "sphere":
                check_png_outputs(formats, sphere_canvas(projection), png_width, len(points))
                points = plot_order(points, points, options, "radians")
                degrees = lon_lat(points)
                write_outputs(
                    outputs,
                    lambda fmt: sphere_output(
                        points, degrees, fmt, coords=coords, projection=projection, view=angles, **settings
                    ),
                )
                return
            shape, ink, points = torus_canvas(points, like, size)
            check_png_outputs(formats, shape[::-1], png_width, len(points))
            unit = points / np.array([shape[1], shape[0]])
            unit = plot_order(physical_centres(unit, shape, settings["width"]), unit, options, settings["width"][1])
            write_outputs(outputs, lambda fmt: torus_output(unit, shape, fmt, ink=ink, **settings))
    except StippleError as error:
        raise click.ClickException(str(error)) from None


def parse_size(text):
    """``"W,H"`` or ``"WxH"`` pixels -> ``(H, W)``; each side from 1 to ``MAX_PIXEL_COORDINATE``."""
    try:
        width, height = (int(part) for part in text.lower().replace("x", ",").split(","))
    except ValueError:
        raise StippleError(f"size must be WIDTH,HEIGHT in pixels, not {text!r}") from None
    if not (1 <= width < MAX_PIXEL_COORDINATE and 1 <= height < MAX_PIXEL_COORDINATE):
        raise StippleError(f"size must be WIDTH,HEIGHT with each in [1, {MAX_PIXEL_COORDINATE - 1}], not {text!r}")
    return height, width


def torus_canvas(pixels, like, size):
    """``(shape, ink, pixels)`` of torus points: the canvas of ``--like`` or ``--size`` with the points wrapped
    onto it, or by default the smallest canvas from the origin that holds every point."""
    if like is None and size is None:
        shape = (int(np.ceil(pixels[:, 1].max(initial=1))), int(np.ceil(pixels[:, 0].max(initial=1))))
        return (max(shape[0], 1), max(shape[1], 1)), None, pixels
    ink = None
    if like is not None:
        weights = load_input(like)
        shape, ink = weights.shape, weights.mean()
    else:
        shape = parse_size(size)
    return shape, ink, np.mod(pixels, np.array([shape[1], shape[0]]))


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
    import json

    from .outputs import commit_outputs, spectrum_plot

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
            if as_line:
                report = evaluate_line_points(points, domain, input_source, bandwidth, options)
            elif names is not None:
                report = evaluate_layers(points, names, input_source, bandwidth, options)
            else:
                report = evaluate_points(domain, points, input_source, bandwidth, kernel, options)
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


def evaluate_line_points(pixels, domain, input_source, bandwidth, options):
    """The report of ``stipple evaluate --line``: E_N of the vertices, length, segments, the drawn line's PSNR."""
    from .evaluate import evaluate_line
    from .line import closed_length, line_problem

    if domain != "torus" or input_source is None:
        raise StippleError("--line needs a CSV of x,y vertices and the image they were drawn from")
    weights = load_input(
        input_source, invert=options["invert"], gamma=options["gamma"], value_range=options["value_range"]
    )
    problem = line_problem(weights, len(pixels), closed_length(pixels), bandwidth, epsilon=1e-10)
    return evaluate_line(problem, pixels / np.array([weights.shape[1], weights.shape[0]]), weights)


def check_extension(option, path, extension):
    """Refuse a report file whose name does not end in ``extension`` (``-`` is stdout)."""
    if path not in (None, "-") and not str(path).lower().endswith(extension):
        raise StippleError(f"{path}: {option} writes {extension} files; the name must end in {extension}")


def evaluate_points(domain, points, input_source, bandwidth, kernel, options):
    """The evaluation report of torus pixels or sphere unit vectors against their input."""
    from .evaluate import evaluate_sphere, evaluate_torus

    if domain == "torus":
        from .torus import torus_problem

        if input_source is None:
            raise StippleError("missing INPUT: the image or map the points were made from")
        weights = load_input(
            input_source, invert=options["invert"], gamma=options["gamma"], value_range=options["value_range"]
        )
        unit = np.mod(points / np.array([weights.shape[1], weights.shape[0]]), 1.0)
        problem = torus_problem(weights, len(points), bandwidth, epsilon=1e-10)
        return evaluate_torus(problem, unit, weights)
    from .sphere import sphere_problem

    density = load_sphere_density(input_source, options)
    problem = sphere_problem(density, len(points), bandwidth, kernel=kernel, epsilon=1e-12)
    return evaluate_sphere(problem, points, density)


def evaluate_layers(pixels, names, input_source, bandwidth, options):
    """The report of all dots against the inks' summed density, with ``classes``: each ink's dots against its
    own density (its count beside its quota ``M · mass share``)."""
    from .colour import parse_palette, separate
    from .evaluate import evaluate_torus
    from .inputs import load_colour
    from .multiclass import class_bandwidth
    from .torus import torus_problem

    if input_source is None:
        raise StippleError("missing INPUT: the colour image the layered points were made from")
    rgb = load_colour(input_source)
    layers = separate(rgb, parse_palette(options["palette"]), options["black"])
    unknown = sorted(set(names.tolist()) - {layer.name for layer in layers})
    if unknown:
        inks = ", ".join(layer.name for layer in layers)
        raise StippleError(f"layers {', '.join(unknown)} are not inks of --palette {options['palette']} ({inks})")
    rows, columns = rgb.shape[:2]
    unit = np.mod(pixels / np.array([columns, rows]), 1.0)
    union = sum(layer.density for layer in layers)
    report = evaluate_torus(torus_problem(union, len(unit), bandwidth, epsilon=1e-10), unit, union)
    report["classes"] = []
    for layer in layers:
        chosen = names == layer.name
        count, share = int(chosen.sum()), float(layer.density.sum() / union.sum())
        entry = {"name": layer.name, "points": count, "mass_share": share, "quota": share * len(unit)}
        if count >= 2:
            band = None if bandwidth is None else class_bandwidth(bandwidth, count, len(unit))
            problem = torus_problem(layer.density, count, band, epsilon=1e-10)
            measured = evaluate_torus(problem, unit[chosen], layer.density)
            entry.update({key: measured[key] for key in ("bandwidth", "energy", "energy_ratio_to_iid")})
            entry["neighbour_distance_over_hexagonal"] = measured.get("neighbour_distance_over_hexagonal")
        report["classes"].append(entry)
    return report


def format_report(report):
    """The evaluation as aligned ``name: value`` lines (the spectrum only as its range)."""
    lines = [
        f"domain: {report['domain']}",
        f"points: {report['points']}",
        f"bandwidth: {report['bandwidth']}",
        f"E_N: {report['energy']:.6e}",
        f"E_N of i.i.d. samples (expected): {report['expected_iid_energy']:.6e}",
        f"ratio to i.i.d.: {report['energy_ratio_to_iid']:.4g}",
        f"untruncated energy (with the near field): {report['untruncated_energy']:.6e}",
    ]
    for item in report.get("similarity", []):
        binned = f" (dots binned into pixels first: PSNR {item['psnr_binned']:.2f} dB)" if "psnr_binned" in item else ""
        lines.append(f"blur sigma {item['sigma']:g} px: PSNR {item['psnr']:.2f} dB, SSIM {item['ssim']:.4f}{binned}")
    if "neighbour_distance_over_hexagonal" in report:
        stats = report["neighbour_distance_over_hexagonal"]
        lines.append("nearest neighbour / hexagonal spacing: " + ", ".join(f"{k} {v:.3f}" for k, v in stats.items()))
    for key in ("length_pixels", "max_over_mean_segment", "min_over_mean_segment"):
        if key in report:
            lines.append(f"{key.replace('_', ' ')}: {report[key]:.6g}")
    for key in ("max_coefficient_error", "minimum_separation_degrees", "cap_discrepancy"):
        if key in report:
            lines.append(f"{key.replace('_', ' ')}: {report[key]:.6g}")
    for item in report.get("classes", []):
        line = f"ink {item['name']}: {item['points']} dots (quota {item['quota']:.2f})"
        if "energy_ratio_to_iid" in item:
            line += f", N {item['bandwidth']}, ratio to i.i.d. {item['energy_ratio_to_iid']:.4g}"
        stats = item.get("neighbour_distance_over_hexagonal") or {}
        if stats:
            line += ", NN / hexagonal " + ", ".join(f"{k} {v:.3f}" for k, v in stats.items())
        lines.append(line)
    return "\n".join(lines)


from .cli_colour import colour  # noqa: E402  (defined beside, registered here)
from .cli_design import design  # noqa: E402

main.add_command(colour)
main.add_command(design)
