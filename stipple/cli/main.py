"""The ``stipple`` command group: every error as one line on stderr, signals unwound cleanly, and the commands.

Exit codes: 0 success; 1 bad data, files or settings; 2 bad usage; 130 / 143 / 129 after SIGINT / SIGTERM / SIGHUP
(once the optimisation has begun a first signal writes the checkpoint and the outputs reached so far; before it,
and for any other signal, every temporary file is removed and every output left whole or untouched). Every error
is one line.
"""

import os
import re
import sys

import click

from .. import __version__
from ..allocator import reuse_freed_memory
from .batch import batch
from .colour import colour
from .design import design
from .evaluate import evaluate
from .line import line
from .render import render
from .sphere import sphere
from .stopped import stopped_line
from .supervise import SIGNALS, Interrupted
from .torus import torus
from .video import video


class StippleGroup(click.Group):
    """The ``stipple`` group: every error is one line on stderr, and signals unwind cleanly.

    Usage errors exit 2, data and file errors 1, SIGINT / SIGTERM / SIGHUP 130 / 143 / 129.
    """

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        reuse_freed_memory()
        open_standard_streams()
        arguments = sys.argv[1:] if args is None else list(args)
        if sys.stdout is None and {"--help", "-h", "--version"} & set(arguments):
            # The help went nowhere with exit 0 (a hostile sweep); '-o -' is refused the same way.
            _error_line("Error: cannot write to stdout: it is closed")
            sys.exit(1)
        try:
            with SIGNALS:
                check_thread_variables(arguments)
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
            _error_line(stopped_line(interruption.number))
            sys.exit(128 + interruption.number)
        sys.exit(code if isinstance(code, int) else 0)


def open_standard_streams():
    """``/dev/null`` on a standard descriptor (0, 1, 2) that the command was started without: a closed stderr's
    number went to the first file the run opened, an output's temporary, which then took the messages (and the
    run failed without a word). stderr's messages go nowhere then; a closed stdout stays refused for ``-``."""
    for number, flags in ((0, os.O_RDONLY), (1, os.O_WRONLY), (2, os.O_WRONLY)):
        try:
            os.fstat(number)
        except OSError:
            opened = os.open(os.devnull, flags)
            if opened != number:
                os.dup2(opened, number)
                os.close(opened)
    if sys.stderr is None:
        sys.stderr = open(os.devnull, "w")  # noqa: SIM115 (for the whole process)
    sys.stderr = MessagesUntilUnread(sys.stderr)


class MessagesUntilUnread:
    """stderr that goes quiet once nobody reads it: ``stipple torus ... 2>&1 | head -1`` stopped the run at its
    next message (BrokenPipeError, exit 1, no output written), where the outputs are the run's result and the
    messages only say how it went. From the first write to a closed pipe on, messages (and descriptor 2) go to
    ``/dev/null``."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._unread()
            return len(text)

    def flush(self):
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._unread()

    def _unread(self):
        quiet = os.open(os.devnull, os.O_WRONLY)
        os.dup2(quiet, 2)
        os.close(quiet)
        self._stream = open(os.devnull, "w")  # noqa: SIM115 (for the rest of the process)

    def __getattr__(self, name):
        return getattr(self._stream, name)


# The thread counts the transform libraries read from the environment: ducc0 stopped the run with a traceback
# on a value that is not a whole number (-1, 1.5, "4,2", empty).
THREAD_VARIABLES = ("OMP_NUM_THREADS", "DUCC0_NUM_THREADS")


def check_thread_variables(args):
    """Refuse, in one line, a thread count in the environment that is not a whole number >= 0 (not for ``--help``
    or ``--version``, which run nothing)."""
    if {"--help", "-h", "--version"} & set(args):
        return
    for name in THREAD_VARIABLES:
        value = os.environ.get(name)
        if value is not None and not re.fullmatch(r"\s*\+?[0-9]+\s*", value):
            raise click.ClickException(f"{name} must be a whole number of threads (or unset), not {value!r}")


def _error_line(text):
    """``text`` on stderr as one line (newlines in messages folded)."""
    click.echo(" ".join(text.split("\n")), err=True)


@click.group(cls=StippleGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="stipple")
def main():
    """Halftoning by discrepancy minimisation on the torus (images) and the sphere (global maps)."""


for command in (torus, sphere, colour, line, design, evaluate, render, video, batch):
    main.add_command(command)
