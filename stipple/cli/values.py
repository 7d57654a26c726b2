"""Values checked where they enter the command line: a click type and an option callback shared by the commands."""

import math

import click

from ..io.sources import EMPTY_NAME
from ..io.units import INTEGER, NUMBER
from .defaults import MAX_POINTS


class DecimalText:
    """Refuses an option's text that Python's ``int()`` and ``float()`` read beyond ASCII decimal notation
    (``-M 3_00`` as 300, other scripts' digits: a hostile sweep); values from config files are numbers already."""

    text = NUMBER
    words = "a decimal number"

    def convert(self, value, param, ctx):
        if isinstance(value, str) and not self.text.fullmatch(value):
            self.fail(f"{value!r} is not {self.words}.", param, ctx)
        return super().convert(value, param, ctx)


class Number(DecimalText, click.types.FloatParamType):
    """A float option's value, written in decimal notation."""


class Integer(DecimalText, click.types.IntParamType):
    """An integer option's value, written in decimal digits."""

    text = INTEGER
    words = "a whole number in decimal digits"


class IntegerRange(DecimalText, click.IntRange):
    """``click.IntRange`` of an option written in decimal digits."""

    text = INTEGER
    words = Integer.words


class FiniteFloatRange(DecimalText, click.FloatRange):
    """``click.FloatRange`` that also refuses nan and the infinities (its range check lets nan through)."""

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number.", param, ctx)
        return number


def some_output(ctx, param, outputs):
    """The ``-o`` files, refused when none is given: a config file's ``output = []`` ran, wrote nothing and
    exited 0 (without -o the default is '-', stdout)."""
    if not outputs:
        raise click.BadParameter("no output: give one or more files, or '-' for stdout", ctx, param)
    for path in outputs:
        if not str(path).strip():
            raise click.BadParameter(EMPTY_NAME, ctx, param)
    return outputs


def checked_count(ctx, param, count):
    """``-M`` checked where it enters, as the library checks it (one line, exit 1): a count below 1 reached the
    PNG's size (a traceback for -M -5), the pen's notes and the peak note before the run refused it."""
    if count is None or count == "auto" or 1 <= count <= MAX_POINTS:
        return count
    raise click.ClickException(f"number of points must be an integer in [1, {MAX_POINTS}], not {count}")
