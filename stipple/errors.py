"""Errors the library raises for bad input; the CLI turns them into one-line messages."""


class StippleError(ValueError):
    """A problem with the user's input, settings or files (exit code 1 in the CLI)."""
