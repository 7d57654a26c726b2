"""Values checked where they enter the command line: a click type and an option callback shared by the commands."""

import math

import click


class FiniteFloatRange(click.FloatRange):
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
            raise click.BadParameter("an empty file name (an unset shell variable?)", ctx, param)
    return outputs
