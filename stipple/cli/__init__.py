"""The command line: one module per command, which parses, converts units, calls one library function and maps
library errors to one line; ``options`` holds the shared option groups, ``supervise`` the run's supervision
(progress, signals, guarded files), ``main`` the ``stipple`` group that registers every command."""

import signal
import sys

from .stopped import stopped_line


def _stopped_while_loading(number, frame):
    # Ctrl-C while the commands' modules load (0.2 s or more on a busy machine) gave a KeyboardInterrupt's traceback
    # (a hostile sweep); nothing has been written yet.
    if sys.stderr is not None:  # started without one: the exit status says it
        sys.stderr.write(stopped_line(number) + "\n")
    sys.exit(128 + number)


def _load():
    """``main``, loaded with SIGINT ending the process in one line (only while loading: a library's or a test
    runner's own handler is given back)."""
    try:
        previous = signal.signal(signal.SIGINT, _stopped_while_loading)
    except ValueError:  # not the main thread: signals are not ours to take
        previous = None
    try:
        from .main import main
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    return main


main = _load()

__all__ = ["main"]
