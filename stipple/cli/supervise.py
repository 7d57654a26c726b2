"""Running a command's optimisation under supervision: the progress bar, SIGINT / SIGTERM, the files guarded
before any work, the outputs committed all-or-nothing, and the summary and exit status at the end."""

import contextlib
import math
import os
import re
import shlex
import signal
import sys
import time

import click

from ..errors import StippleError
from ..io.commit import FORMATS, check_writable, commit_outputs, output_format, taken_signals
from ..io.safety import CheckpointLock, check_distinct
from ..io.sources import EMPTY_NAME
from .defaults import MAX_ITERATIONS
from .options import given_on_command_line


class Progress:
    """A tqdm bar on stderr (energy, relative gradient norm, speed); off when quiet or stderr is not a TTY.

    A run has phases (the coarse levels, the main run, the spread step, the correction), each counting from 0 and
    most stopping when the energy settles: each phase gets a bar of its own, which shows its count and speed, not
    a total (the iteration cap is rarely reached: a 5 s run showed 113/2000 with 1:30 to go, and its count fell
    back between phases). The last phase's bar stays."""

    def __init__(self, enabled):
        self.enabled = enabled
        self.bar = None

    def __call__(self, state):
        if not self.enabled:
            return False
        if self.bar is not None and state.iteration < self.bar.n:
            self.bar.leave = False
            self.bar.close()
            self.bar = None
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(initial=state.iteration, unit="it", file=sys.stderr, dynamic_ncols=True)
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
    """SIGINT / SIGTERM / SIGHUP (``taken_signals``) for the whole command.

    While the optimiser runs (``deferred``, once the work has begun: ``begin``) the first signal only asks it to stop
    after the current iteration, so that the checkpoint and the outputs reached so far are written; any other signal
    raises ``Interrupted``, which removes temporary files and releases locks on its way out (exit 130 / 143 / 129);
    signals that arrive while it unwinds are ignored, so that the cleanup itself is never cut short. Before the
    work begins (the input still being read: a pipe with no writer yet) a signal interrupts at once.
    """

    def __init__(self):
        self.signal = None
        self.deferring = False
        self.started = False
        self.unwinding = False
        self._previous = {}

    def __enter__(self):
        self.signal, self.deferring, self.started, self.unwinding = None, False, False, False
        for number in taken_signals():
            try:
                self._previous[number] = signal.signal(number, self._handle)
            except ValueError:  # not the main thread: leave signals alone
                break
        return self

    def __exit__(self, *exc):
        # After a signal the command only exits: a second one (a second Ctrl-C, or ``timeout``'s signal to the
        # process group) is ignored, else it interrupts the interpreter's wait for worker threads with a traceback.
        stopping = self.signal is not None or self.unwinding
        for number, handler in self._previous.items():
            # None: a handler installed outside Python (stipple embedded in a C program), which cannot be put back.
            signal.signal(number, signal.SIG_IGN if stopping else (signal.SIG_DFL if handler is None else handler))
        self._previous.clear()

    def _handle(self, number, frame):
        if self.deferring and self.started and self.signal is None:
            self.signal = number
            return
        if self.unwinding:  # already on the way out: let the cleanup finish
            return
        self.unwinding = True
        raise Interrupted(number)

    @contextlib.contextmanager
    def deferred(self):
        """Within the block, once the work has begun (``begin``), a first signal is only recorded."""
        self.deferring, self.started = True, False
        try:
            yield self
        finally:
            self.deferring = False

    def begin(self):
        """Mark the work that a first signal lets finish as begun (the optimiser's first state, a video's first
        frame, replayed or new): from now on a first signal is only recorded."""
        self.started = True

    def stop_requested(self, state):
        """The optimiser's callback: whether a signal asked it to stop; the run has begun (``begin``)."""
        self.begin()
        return self.signal is not None


SIGNALS = SignalGuard()


def checkpoint_interval(options):
    """``(seconds, iterations)`` of ``--checkpoint-every``, refused when given on the command line without
    ``--checkpoint`` (it would be ignored; a config file may set it for the runs that checkpoint); ``--init`` with
    ``--resume`` is refused too (the resumed run ignored it)."""
    interval = parse_every(options["checkpoint_every"])
    context = click.get_current_context(silent=True)
    if given_on_command_line(context, "checkpoint_every") and options.get("checkpoint") is None:
        raise StippleError("--checkpoint-every is for --checkpoint: without it, it would be ignored")
    if given_on_command_line(context, "init") and options.get("resume"):
        raise StippleError("--init is for a new run: --resume continues from the checkpoint's points")
    return interval


def parse_every(text):
    """``"60s"``, ``"5m"`` (seconds) or ``"100"`` / ``"100it"`` (iterations) -> (seconds, iterations)."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*(s|m|h|it)?\s*", str(text))
    if not match or float(match.group(1)) <= 0:
        raise StippleError(f"checkpoint-every must be like 60s, 5m or 100 (iterations), not {text!r}")
    value, unit = float(match.group(1)), match.group(2) or "it"
    if unit == "it":
        if value != int(value) or value > MAX_ITERATIONS:
            raise StippleError(
                f"checkpoint-every must be a whole number of iterations up to {MAX_ITERATIONS}, not {text!r}"
            )
        return None, int(value)
    seconds = value * {"s": 1, "m": 60, "h": 3600}[unit]
    if not math.isfinite(seconds):
        raise StippleError(f"checkpoint-every must be a finite time, not {text!r}")
    return seconds, None


@contextlib.contextmanager
def guarded_files(inputs, outputs, checkpoint=None, reports=(), formats=FORMATS):
    """Check every file of a run before any work, then hold the checkpoint's lock for the whole run.

    ``inputs`` and ``reports`` are ``(role, path)`` pairs (files read; extra files written). Outputs'
    formats (one of ``formats``) and directories are checked, no output may name an input, the checkpoint
    or another output, and ``-`` (stdout) may be given once.
    """
    for path in outputs:
        output_format(path, formats)
        check_writable(path)
    for _, path in reports:
        check_writable(path)
    if list(outputs).count("-") > 1:
        raise StippleError("'-' (stdout) may be given only once")
    if checkpoint is not None and not str(checkpoint).strip():  # found only when it was written, after the run
        raise StippleError(f"--checkpoint: {EMPTY_NAME}")
    if checkpoint is not None and str(checkpoint) == "-":
        raise StippleError("--checkpoint must name a file, not '-': a checkpoint is saved, replaced and resumed")
    piped = [role for role, path in inputs if path is not None and str(path) == "-"]
    if len(piped) > 1:
        raise StippleError(f"'-' (stdin) may be given only once, not for both {' and '.join(piped)}")
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


def echo_notes(lines):
    """Each of ``lines`` on stderr as a note ("stipple: note: ...")."""
    for line in lines:
        click.echo(f"stipple: note: {line}", err=True)


def write_outputs(paths, files, quiet=False):
    """Write every output all-or-nothing (``-`` is stdout): ``files`` maps each format to its bytes; its drawing's
    ``warnings`` (dots left out) go to stderr unless ``quiet``."""
    commit_outputs([(path, files[output_format(path)]) for path in paths])
    if not quiet:
        echo_notes(getattr(files, "warnings", ()))


def solve(problem, options, init, stop=None):
    """Run ``problem`` with the CLI's stopping, checkpoint, progress and signal options (and ``stop``, a callback
    that ends the run by returning True)."""
    from ..halftone import run

    announce = announcer(options)
    result, stopped_by = supervised(
        options,
        lambda keywords: run(problem, init=init, **run_keywords(options), **keywords),
        stop,
        None if announce is None else lambda: announce(problem),
    )
    report_run(result, options)
    return result, stopped_by


def run_keywords(options):
    """The keywords of ``halftone.run`` that the command's options set besides ``supervised``'s."""
    return {
        "safeguard": options["safeguard"],
        "correct": options.get("correct", False),
        "settle": options.get("settle"),
    }


def announcer(options):
    """With ``--verbose``: ``announce(problem)``, one line of the problem's settings before it runs; else None."""
    if not options["verbose"] or options["quiet"]:
        return None

    def announce(problem):
        from ..halftone import default_threads

        fourier = problem.discrepancy.fourier
        details = ", ".join(f"{key}={value}" for key, value in problem.settings.items())
        threads = options.get("threads") or default_threads()
        share = f"transforms {fourier.threads}"
        adjoints = getattr(fourier, "adjoint_threads", fourier.threads)
        if adjoints != fourier.threads:
            share += f", adjoints {adjoints}"
        click.echo(
            f"stipple: {details}, threads={threads} ({share}), epsilon={fourier.epsilon:g}, "
            f"tol={options['tol']:g}, iterations<={options['iterations']}",
            err=True,
        )

    return announce


def report_run(result, options):
    """With ``--verbose``: the time per iteration and the energy's course."""
    if options["verbose"] and not options["quiet"] and len(result.energies) > 1:
        import numpy as np

        rises = int(np.sum(np.diff(result.energies) > 0))
        click.echo(
            f"stipple: {result.seconds / max(result.iterations, 1) * 1000:.1f} ms per iteration, "
            f"energy {result.energies[0]:.4e} -> {result.energy:.4e} ({rises} rises)",
            err=True,
        )


def supervised(options, launch, stop=None, announce=None):
    """``launch(keywords)`` under the CLI's progress bar and signal handling, where ``keywords`` are the stopping,
    seed, callback and checkpoint arguments that ``halftone.run`` and ``draw_line`` share. The callback also ends
    the run when ``stop`` returns True, and ``announce()`` reports the settings between the checks of the
    checkpoint interval and of the seed. Returns the result and the signal that stopped it (or None)."""
    from ..halftone import chain_callbacks, check_integer

    seconds, iterations = checkpoint_interval(options)
    if announce is not None:
        announce()
    check_integer("seed", options["seed"], 0, 2**63 - 1)
    progress = Progress(not options["quiet"] and sys.stderr.isatty())
    with SIGNALS.deferred() as interruption:
        try:
            result = launch(
                {
                    "seed": options["seed"],
                    "tol": options["tol"],
                    "iterations": options["iterations"],
                    "time_limit": options["time_limit"],
                    "callback": chain_callbacks(progress, interruption.stop_requested, stop),
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


def finish(result, stopped_by, options, started, reached=None, energy=True):
    """Summary on stderr, and the exit code after a signal (130 / 143) with how to resume.

    ``reached`` says how far a stopped run got and what it wrote (default: its iteration; outputs written);
    ``energy`` whether the summary gives the final energy.
    """
    if stopped_by is not None:
        name = signal.Signals(stopped_by).name
        if options["checkpoint"] and os.path.exists(options["checkpoint"]):
            command = shlex.join(["stipple"] + sys.argv[1:] + ([] if options["resume"] else ["--resume"]))
            hint = f"resume with: {command}"
        elif options["checkpoint"]:
            hint = "it stopped before its first checkpoint, so there is nothing to resume: run the command again"
        else:
            hint = "no --checkpoint was given, so the run cannot be resumed"
        reached = f"at iteration {result.iterations}; outputs written" if reached is None else reached
        click.echo(f"stipple: stopped by {name} {reached}; {hint}", err=True)
        sys.exit(128 + stopped_by)
    if not options["quiet"]:
        summary = f"E={result.energy:.6e}; " if energy else ""
        click.echo(f"stipple: {result.message}; {summary}{time.perf_counter() - started:.1f} s", err=True)


def plot_order(centres, points, options, unit):
    """``points`` reordered along a short pen path through ``centres`` when ``--order`` is given."""
    if not options.get("order"):
        return points
    if options["order"] == "progressive":
        raise StippleError("--order progressive is for stipple torus with one ink; use --order here")
    from ..render.pen import pen_order

    points, before, after = pen_order(points, centres)
    if not options.get("quiet"):
        click.echo(f"stipple: pen-up travel {before:.4g} -> {after:.4g} {unit}", err=True)
    return points
