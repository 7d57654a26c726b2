"""``--config FILE.toml`` for the CLI: a TOML table of option values that become the command's defaults."""

import os
import tomllib

import click

CONFIG_ALIASES = {"points": "n_points", "output": "outputs", "range": "value_range", "input": None}
PATH_KEYS = ("outputs", "init", "checkpoint")


def load_config(ctx, param, value):
    """Read ``--config FILE.toml`` into the command's defaults (options on the command line win).

    Keys are the long option names (``points``, ``bandwidth``, ``tol``, ``output``, ...) and ``input`` for
    the IMAGE/MAP argument; relative paths are relative to the config file. Unknown keys and values
    of the wrong type are errors naming the key.
    """
    if value is None:
        return None
    try:
        with open(value, "rb") as stream:
            table = tomllib.load(stream)
    except OSError as error:
        raise click.BadParameter(f"cannot read {value}: {error.strerror}", ctx, param) from None
    except tomllib.TOMLDecodeError as error:
        raise click.BadParameter(f"{value} is not valid TOML: {error}", ctx, param) from None
    base = os.path.dirname(os.path.abspath(value))
    parameters = {p.name: p for p in ctx.command.params if p.name != "config"}
    defaults = {}
    for key, item in table.items():
        name = CONFIG_ALIASES.get(key, key.replace("-", "_"))
        if key == "input":
            if not isinstance(item, str):
                raise click.BadParameter(f"key 'input' in {value}: expected a path or builtin:NAME", ctx, param)
            defaults["input"] = _resolve_paths(base, item)
            continue
        if name not in parameters or isinstance(parameters[name], click.Argument):
            raise click.BadParameter(f"unknown key {key!r} in {value}", ctx, param)
        if isinstance(item, bool) != getattr(parameters[name], "is_flag", False):
            raise click.BadParameter(f"key {key!r} in {value}: wrong type {type(item).__name__}", ctx, param)
        try:
            converted = parameters[name].type_cast_value(ctx, item)
        except click.BadParameter as error:
            raise click.BadParameter(f"key {key!r} in {value}: {error.message}", ctx, param) from None
        if name in PATH_KEYS:
            converted = _resolve_paths(base, converted)
        defaults[name] = converted
    ctx.default_map = {**(ctx.default_map or {}), **defaults}
    return value


def _resolve_paths(base, value):
    """Paths in a config are relative to its folder; ``-``, keywords and ``builtin:`` names stay as they are."""
    if isinstance(value, tuple):
        return tuple(_resolve_paths(base, item) for item in value)
    keep = value is None or value in ("-", "density", "uniform") or value.startswith("builtin:")
    return value if keep or os.path.isabs(value) else os.path.join(base, value)
