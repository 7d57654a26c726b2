"""The command line: one module per command, which parses, converts units, calls one library function and maps
library errors to one line; ``options`` holds the shared option groups, ``supervise`` the run's supervision
(progress, signals, guarded files), ``main`` the ``stipple`` group that registers every command."""

from .main import main

__all__ = ["main"]
