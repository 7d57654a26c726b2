"""The package's layout: no import cycles, no module over 450 lines, click and tqdm only in the command line.

Imports are read from the source (function-level imports included), so a cycle hidden behind a lazy import is
found too.
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "stipple"
MAX_LINES = 450
# Modules allowed to import click or tqdm: the command line, the vpype plugin and ``python -m stipple``.
INTERFACE = ("stipple.cli", "stipple.vpype_plugin", "stipple.__main__")


def module_name(path):
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules():
    return {module_name(path): path for path in sorted(PACKAGE.rglob("*.py"))}


def is_package(name, known):
    return any(other.startswith(name + ".") for other in known)


def imports_of(name, path, known):
    """The set of modules of the package that ``name`` imports, and every top-level library it imports."""
    inside, outside = set(), set()
    base = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                target = alias.name
                (inside if target.split(".")[0] == "stipple" else outside).add(target)
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                target = node.module
                if target.split(".")[0] != "stipple":
                    outside.add(target)
                    continue
            else:
                anchor = base.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                target = ".".join(anchor + ([node.module] if node.module else []))
            for alias in node.names:
                # ``from . import allocator`` names a module; ``from .torus import torus_problem`` a name in one.
                child = f"{target}.{alias.name}"
                inside.add(child if child in known else target)
    return {module for module in inside if module in known and module != name}, outside


def graph():
    known = modules()
    return {name: imports_of(name, path, known)[0] for name, path in known.items()}


def find_cycle(edges):
    """One import cycle as a list of modules, or None (depth-first search with colours)."""
    state, stack = {}, []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for target in sorted(edges.get(node, ())):
            if state.get(target) == "open":
                return stack[stack.index(target) :] + [target]
            if target not in state:
                found = visit(target)
                if found:
                    return found
        stack.pop()
        state[node] = "done"
        return None

    for node in sorted(edges):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


def test_the_cycle_finder_finds_a_lazy_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) is None


def test_the_import_reader_sees_relative_and_lazy_imports(tmp_path):
    source = tmp_path / "probe.py"
    source.write_text("def f():\n    from .io.points import read_points\n    from . import allocator\n")
    known = modules()
    inside, _ = imports_of("stipple.probe", source, known)
    assert inside == {"stipple.io.points", "stipple.allocator"}


def test_no_import_cycles():
    cycle = find_cycle(graph())
    assert cycle is None, " -> ".join(cycle)


@pytest.mark.parametrize("name", sorted(modules()))
def test_no_module_over_450_lines(name):
    lines = modules()[name].read_text().count("\n")
    assert lines <= MAX_LINES, f"{name} has {lines} lines"


@pytest.mark.parametrize("name", sorted(modules()))
def test_only_the_command_line_imports_click_or_tqdm(name):
    if name.startswith(INTERFACE):
        return
    _, outside = imports_of(name, modules()[name], modules())
    assert not {module.split(".")[0] for module in outside} & {"click", "tqdm"}, name


def test_the_public_api_is_where_it_was():
    import stipple
    from stipple.line import draw_line

    for name in ("halftone_torus", "halftone_sphere", "spherical_design", "load_density"):
        assert callable(getattr(stipple, name)), name
    assert callable(draw_line)
