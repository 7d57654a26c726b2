"""``--config FILE.toml`` for the CLI: a TOML table of option values that become the command's defaults."""

import math
import os
import tomllib

import click

PATH_KEYS = ("outputs", "init", "checkpoint")
MAX_CONFIG_BYTES = 1 << 20


def load_config(ctx, param, value):
    """Read ``--config FILE.toml`` into the command's defaults (options on the command line win).

    Keys are the long option names (``points``, ``bandwidth``, ``tol``, ``output``, ...) and ``input`` for
    the IMAGE/MAP argument; relative paths are relative to the config file. Unknown keys and values
    of the wrong type are errors naming the key.
    """
    if value is None:
        return None
    table = _read_table(value, ctx, param)
    ctx.meta["stipple.config"] = value
    base = os.path.dirname(os.path.abspath(value))
    options = config_keys(ctx.command)
    defaults, keys = {}, {}
    for key, item in table.items():
        if key == "input":
            if not isinstance(item, str):
                raise click.BadParameter(f"key 'input' in {value}: expected a path or builtin:NAME", ctx, param)
            defaults["input"] = _resolve_paths(base, item)
            continue
        if key not in options:
            raise click.BadParameter(f"unknown key {key!r} in {value}", ctx, param)
        option = options[key]
        if option.name in keys:  # frame-iterations and frame_iterations, both in one table
            raise click.BadParameter(f"keys {keys[option.name]!r} and {key!r} in {value} are one option", ctx, param)
        keys[option.name] = key
        if isinstance(item, bool) != getattr(option, "is_flag", False):
            raise click.BadParameter(f"key {key!r} in {value}: wrong type {type(item).__name__}", ctx, param)
        item = _shaped(option, item, f"key {key!r} in {value}", ctx, param)
        converted = _convert(option, item, f"key {key!r} in {value}", ctx, param)
        if option.name in PATH_KEYS:
            converted = _resolve_paths(base, converted)
        defaults[option.name] = converted
    ctx.default_map = {**(ctx.default_map or {}), **defaults}
    return value


def config_keys(command):
    """A config file's keys -> ``command``'s options: each long option name, with ``-`` or ``_`` (``points``,
    ``frame-iterations``, ``frame_iterations``); not the options' internal names (``n_points`` was taken)."""
    keys = {}
    for parameter in command.params:
        if isinstance(parameter, click.Option) and parameter.name != "config":
            for name in parameter.opts:
                if name.startswith("--"):
                    keys[name[2:]] = keys[name[2:].replace("-", "_")] = parameter
    return keys


def _read_table(path, ctx, param):
    """The TOML table of ``path`` (UTF-8, at most ``MAX_CONFIG_BYTES``; a byte-order mark, as some editors on
    Windows write, is skipped)."""
    try:
        with open(path, "rb") as stream:
            data = stream.read(MAX_CONFIG_BYTES + 1)
    except OSError as error:
        raise click.BadParameter(f"cannot read {path}: {error.strerror}", ctx, param) from None
    if len(data) > MAX_CONFIG_BYTES:
        raise click.BadParameter(f"{path} is longer than {MAX_CONFIG_BYTES} bytes; not a config file", ctx, param)
    try:
        return tomllib.loads(data.decode("utf-8-sig"))
    except UnicodeDecodeError:
        raise click.BadParameter(f"{path} is not UTF-8 text", ctx, param) from None
    except (tomllib.TOMLDecodeError, RecursionError) as error:
        raise click.BadParameter(f"{path} is not valid TOML: {error}", ctx, param) from None


def _shaped(parameter, item, where, ctx, param):
    """A repeatable option's one value as a list of one (``output = "a.csv"``); a list refused where the option
    takes one value (``palette = ["red", "black"]`` was read as the text of the list)."""
    if getattr(parameter, "multiple", False):
        return [item] if not isinstance(item, list) else item
    if isinstance(item, list) and parameter.nargs == 1:
        raise click.BadParameter(f"{where}: expected one value, not a list", ctx, param)
    return item


def _convert(parameter, item, where, ctx, param):
    """``item`` converted by the option's own type; floats for integer options and non-finite numbers refused."""
    expects_integer = isinstance(parameter.type, click.types.IntParamType)
    for number in item if isinstance(item, list) else [item]:
        if isinstance(number, (list, dict)) or (parameter.name in PATH_KEYS and not isinstance(number, str)):
            # output = [["a.csv"]] was read as the file "['a.csv']", output = ["a.csv", 5] as a file "5" (a sweep)
            raise click.BadParameter(f"{where}: expected text, not {type(number).__name__} {number!r}", ctx, param)
        if isinstance(number, str) and _numeric(parameter.type) and _number_text(number):
            # points = "100" passed (docs/errors.md: numbers, not text); a word such as "auto" is the type's to judge
            raise click.BadParameter(f"{where}: expected a number, not the text {number!r}", ctx, param)
        if isinstance(number, float) and (expects_integer or not math.isfinite(number)):
            kind = "an integer" if expects_integer else "a finite number"
            raise click.BadParameter(f"{where}: expected {kind}, not {number!r}", ctx, param)
    try:
        return parameter.type_cast_value(ctx, item)
    except click.BadParameter as error:
        raise click.BadParameter(f"{where}: {error.message}", ctx, param) from None
    except (TypeError, ValueError, OverflowError) as error:
        raise click.BadParameter(f"{where}: {error}", ctx, param) from None


def _number_text(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def _numeric(kind):
    """Whether an option's type takes numbers only (a tuple's: all its members)."""
    numbers = (click.types.IntParamType, click.types.FloatParamType)
    if isinstance(kind, click.Tuple):
        return all(isinstance(member, numbers) for member in kind.types)
    return isinstance(kind, numbers)


def _resolve_paths(base, value):
    """Paths in a config are relative to its folder; ``-``, keywords and ``builtin:`` names stay as they are."""
    if isinstance(value, tuple):
        return tuple(_resolve_paths(base, item) for item in value)
    keywords = ("-", "stratified", "density", "uniform", "auto", "lattice")
    # An empty name stays empty, for the command's own "an empty file name" (it became the config's folder).
    keep = value is None or value in ("", *keywords) or value.startswith("builtin:")
    return value if keep or os.path.isabs(value) else os.path.join(base, value)
