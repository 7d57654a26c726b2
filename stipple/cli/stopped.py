"""The one line of a run stopped by a signal (``main``'s, and ``stipple.cli``'s while the commands load)."""

import signal


def stopped_line(number):
    """The one line of a run stopped by signal ``number``."""
    name = signal.Signals(number).name
    return f"stipple: stopped by {name}; outputs are whole or untouched, no temporary file left"
