"""The package's layout: the layers (each imports only from its own and the layers below it), no import cycles,
no module over 450 lines, no function over 80 lines of code, click and tqdm only in the command line, and the path
of ``stipple torus IMAGE -o out.png`` entering each layer once, top to bottom.

Imports are read from the source (function-level imports included), so a cycle or an upward import hidden behind
a lazy import is found too.
"""

import ast
from pathlib import Path

import numpy as np
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "stipple"
MAX_LINES = 450
MAX_FUNCTION_LINES = 80
# The layers, top to bottom (docs/architecture.md): a module's layer is that of the longest prefix listed.
LAYERS = {
    "stipple.cli": "interface",
    "stipple.vpype_plugin": "interface",
    "stipple.__main__": "interface",
    "stipple.pipelines": "pipelines",
    "stipple.batch": "pipelines",
    "stipple": "method",
    "stipple.io": "io",
    "stipple.errors": "utilities",
    "stipple.checks": "utilities",
    "stipple.allocator": "utilities",
    "stipple.parallel": "utilities",
    "stipple.lazy": "utilities",
}
ORDER = ("interface", "pipelines", "method", "io", "utilities")
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


def layer(name):
    """The layer of module ``name`` (the package ``stipple`` itself, whose public names load lazily, is its own)."""
    if name == "stipple":
        return "interface"
    prefix = max((p for p in LAYERS if name == p or name.startswith(p + ".")), key=len)
    return LAYERS[prefix]


def test_every_module_has_a_layer():
    assert layer("stipple.io.points") == "io" and layer("stipple.line.draw") == "method"
    assert layer("stipple.pipelines.image") == "pipelines" and layer("stipple.cli.torus") == "interface"
    assert {layer(name) for name in modules()} == set(ORDER)


def test_each_module_imports_only_its_own_and_lower_layers():
    upward = [
        f"{name} ({layer(name)}) imports {target} ({layer(target)})"
        for name, targets in graph().items()
        for target in targets
        if ORDER.index(layer(target)) < ORDER.index(layer(name))
    ]
    assert upward == []


def test_io_imports_nothing_above_it():
    """Readers make arrays of bytes and writers bytes of a finished drawing: no problem, no drawing decision."""
    above = {
        name: sorted(target for target in targets if layer(target) not in ("io", "utilities"))
        for name, targets in graph().items()
        if layer(name) == "io"
    }
    assert {name: targets for name, targets in above.items() if targets} == {}


def test_only_the_batch_command_imports_the_batch_module():
    importers = {name for name, targets in graph().items() if "stipple.batch" in targets}
    assert importers == {"stipple.cli.batch"}


def test_nothing_outside_the_command_line_imports_it():
    importers = {
        name
        for name, targets in graph().items()
        if any(target.startswith("stipple.cli") for target in targets) and not name.startswith("stipple.cli")
    }
    assert importers <= {"stipple.__main__"}


def code_lines(function, source_lines):
    """Lines of code of a function: not blank, not a comment, not its docstring."""
    body = function.body
    skip = set()
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        skip = set(range(body[0].lineno, body[0].end_lineno + 1))
    return sum(
        1
        for number in range(function.lineno, function.end_lineno + 1)
        if number not in skip
        and source_lines[number - 1].strip()
        and not source_lines[number - 1].strip().startswith("#")
    )


@pytest.mark.parametrize("name", sorted(modules()))
def test_no_function_over_80_lines_of_code(name):
    source = modules()[name].read_text()
    lines = source.splitlines()
    long = [
        f"{node.name}: {code_lines(node, lines)}"
        for node in ast.walk(ast.parse(source))
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and code_lines(node, lines) > MAX_FUNCTION_LINES
    ]
    assert long == [], name


def test_the_function_counter_skips_docstrings_comments_and_blanks():
    source = 'def f():\n    """Doc\n    string."""\n\n    # a comment\n    x = 1\n    return x\n'
    function = ast.parse(source).body[0]
    assert code_lines(function, source.splitlines()) == 3


def handed_down(frame):
    """Whether the function running in ``frame`` was handed to its caller (a local of the caller's frame, or an
    item of a list or tuple there): a callback, such as the CG's progress callback or a block worker."""
    code = frame.f_code
    for value in frame.f_back.f_locals.values():
        for item in value if isinstance(value, (list, tuple)) else (value,):
            item = getattr(item, "func", item)  # functools.partial
            function = getattr(item, "__func__", item)
            method = vars(type(item)).get("__call__")
            if code in (getattr(function, "__code__", None), getattr(method, "__code__", None)):
                return True
    return False


def test_the_image_of_stipple_torus_enters_each_layer_once_top_to_bottom(tmp_path):
    """Every call between the package's functions on the path of ``stipple torus IMAGE -o out.png``, traced: the
    command line enters the pipelines once (``stipple_image``), and no call climbs back up a layer except to a
    function handed down as an argument (the CG's progress and signal callback, the tone hints, a worker of
    ``parallel``). Calls may skip layers downwards: the command line checks the output paths with ``io.commit``
    before any work."""
    import sys

    from click.testing import CliRunner
    from PIL import Image

    from stipple.cli import main

    image = tmp_path / "in.png"
    Image.fromarray((np.arange(24 * 32).reshape(24, 32) % 251).astype(np.uint8)).save(image)
    arguments = ["torus", str(image), "-M", "60", "-N", "16", "--iterations", "3", "--threads", "1"]
    edges, entered = set(), []

    def trace(frame, event, _):
        if event != "call" or frame.f_back is None:
            return
        callee, caller = frame.f_globals.get("__name__", ""), frame.f_back.f_globals.get("__name__", "")
        if not callee.startswith("stipple") or frame.f_code.co_name == "<module>":
            return
        if not entered or entered[-1] != layer(callee):
            entered.append(layer(callee))
        if caller.startswith("stipple") and frame.f_back.f_code.co_name != "<module>":
            edges.add((layer(caller), layer(callee), f"{callee}.{frame.f_code.co_name}", handed_down(frame)))

    sys.setprofile(trace)
    try:
        result = CliRunner().invoke(main, [*arguments, "-q", "-o", str(tmp_path / "out.png")])
    finally:
        sys.setprofile(None)
    assert result.exit_code == 0, result.output
    assert set(entered) == set(ORDER)
    upward = sorted(
        (caller, callee, function)
        for caller, callee, function, callback in edges
        if ORDER.index(callee) < ORDER.index(caller) and not callback
    )
    assert upward == [], upward
    callbacks = {function for caller, callee, function, callback in edges if callback}
    assert "stipple.cli.torus.<lambda>" in callbacks  # the tracer sees callbacks: the tone hints
    into_pipelines = {
        function for caller, callee, function, _ in edges if (caller, callee) == ("interface", "pipelines")
    }
    # Besides making the recipe (``TorusRecipe``), one call: the pipeline run.
    assert into_pipelines - {"stipple.pipelines.image.__init__"} == {"stipple.pipelines.image.stipple_image"}
