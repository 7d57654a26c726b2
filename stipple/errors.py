"""Errors the library raises for bad input; the CLI turns them into one-line messages."""


class StippleError(ValueError):
    """A problem with the user's input, settings or files (exit code 1 in the CLI)."""


class MissingInput(StippleError):
    """A required input (IMAGE, MAP, INPUT) not given: bad usage (exit code 2 in the CLI, as a missing argument)."""
