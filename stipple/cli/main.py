"""The ``stipple`` command group: every error as one line on stderr, signals unwound cleanly, and the commands.

Exit codes: 0 success; 1 bad data, files or settings; 2 bad usage; 130 / 143 / 129 after SIGINT / SIGTERM / SIGHUP
(during the optimisation a first signal writes the checkpoint and the outputs reached so far; any other
signal removes every temporary file and leaves every output whole or untouched). Every error is one line.
"""

import signal
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


@click.group(cls=StippleGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="stipple")
def main():
    """Halftoning by discrepancy minimisation on the torus (images) and the sphere (global maps)."""


for command in (torus, sphere, colour, line, design, evaluate, render, video, batch):
    main.add_command(command)
