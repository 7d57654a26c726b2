"""Every command of ``stipple``: its ``--help``, and one tiny run that writes its files."""

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main

COMMANDS = ("batch", "colour", "design", "evaluate", "line", "render", "sphere", "torus", "video")


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_every_command_is_registered():
    assert sorted(main.commands) == sorted(COMMANDS)


@pytest.mark.parametrize("command", COMMANDS)
def test_help(command):
    result = run([command, "--help"])
    assert result.exit_code == 0, result.output
    assert result.output.startswith("Usage: ") and f" {command} [OPTIONS]" in result.output.splitlines()[0]
    assert "--help" in result.output


@pytest.mark.parametrize(
    "command, option",
    [
        ("line", "--dot-style"),
        ("line", "--order"),
        ("line", "--dot-radius"),
        ("line", "--near-field"),
        ("line", "--safeguard"),
        ("colour", "--invert"),
        ("colour", "--color"),
        ("design", "--order"),
        ("design", "--style"),
        ("video", "--order"),
        ("video", "--verbose"),
    ],
)
def test_a_command_offers_only_the_options_that_act_on_it(command, option):
    """An option that would do nothing is not offered: a usage error naming it, not a silent no-op."""
    result = run([command, option, "--help"])
    assert result.exit_code == 2 and f"No such option '{option}'" in result.output, result.output
    assert option not in run([command, "--help"]).output.replace(f"{option}-", "")


def test_the_help_defaults_are_the_librarys():
    """``stipple.cli.defaults`` repeats the library's choices so that --help needs no numpy: each must match."""
    from stipple import halftone, nufft, optimize, video
    from stipple.cli import defaults
    from stipple.line import LINE_ITERATIONS
    from stipple.measures import plot_estimate
    from stipple.pipelines import pen

    assert defaults.BETAS == optimize.BETAS and defaults.SETTLE_WINDOW == optimize.SETTLE_WINDOW
    assert defaults.INITS == halftone.INITS and defaults.DEFAULT_SETTLE == halftone.DEFAULT_SETTLE
    assert defaults.MAX_POINTS == halftone.MAX_POINTS and defaults.MAX_ITERATIONS == halftone.MAX_ITERATIONS
    assert defaults.BACKENDS == nufft.BACKENDS
    assert defaults.FRAME_ITERATIONS == video.FRAME_ITERATIONS
    assert defaults.LINE_ITERATIONS == LINE_ITERATIONS
    assert defaults.DEFAULT_SPEED == plot_estimate.DEFAULT_SPEED
    assert defaults.DEFAULT_TRAVEL_SPEED == plot_estimate.DEFAULT_TRAVEL_SPEED
    assert defaults.DEFAULT_LIFT == plot_estimate.DEFAULT_LIFT
    assert defaults.ORDERS == pen.ORDERS


def test_the_command_line_loads_without_numpy():
    """``stipple --help``, ``stipple COMMAND --help`` and usage errors import no numpy, scipy or the method: each
    command imports the library inside its function (the import, not a clock, is what is checked)."""
    import subprocess
    import sys

    code = (
        "import sys; import stipple.cli.main; "
        "heavy = sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'scipy', 'PIL', 'ducc0', 'finufft') "
        "or m in ('stipple.halftone', 'stipple.torus', 'stipple.sphere')); print(heavy)"
    )
    output = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert output.strip() == "[]"


@pytest.fixture
def image(tmp_path):
    rows, columns = np.mgrid[0:20, 0:30]
    rgb = np.stack([columns * 8, rows * 12, 255 - columns * 8], axis=-1).astype(np.uint8)
    path = tmp_path / "in.png"
    Image.fromarray(rgb).save(path)
    return path


def tiny_runs(image, folder):
    """One small run per command, each writing a file under ``folder``."""
    dots = folder / "dots.csv"
    return {
        "torus": ["torus", image, "-M", 60, "-N", 12, "--iterations", 3, "-o", dots, "-o", folder / "t.svg"],
        "sphere": ["sphere", "--uniform", "-M", 30, "-N", 4, "--iterations", 3, "-o", folder / "s.geojson"],
        "colour": ["colour", image, "-M", 80, "-N", 12, "--iterations", 3, "-o", folder / "c.csv"],
        "line": ["line", image, "-M", 40, "--iterations", 3, "-o", folder / "l.svg"],
        "design": ["design", "-t", 3, "--iterations", 50, "-o", folder / "d.csv"],
        "render": ["render", dots, "--like", image, "-o", folder / "r.png"],
        "evaluate": ["evaluate", dots, image, "--json", folder / "e.json"],
        "video": ["video", folder / "in.p?g", "-M", 50, "-N", 12, "--iterations", 3, "-o", folder / "v.csv"],
        "batch": ["batch", image, "-M", 50, "-N", 12, "--iterations", 3, "-d", folder, "--format", "csv"],
    }


def test_one_tiny_run_per_command(image, tmp_path):
    runs = tiny_runs(image, tmp_path)
    assert sorted(runs) == sorted(COMMANDS)
    for command, args in runs.items():  # in order: render and evaluate read the torus run's dots
        result = run([*args, "-q"] if command not in ("evaluate",) else args)
        assert result.exit_code == 0, f"{command}: {result.output}"
        written = args[args.index("--json") + 1] if command == "evaluate" else args[-1]
        written = tmp_path / "in.csv" if command == "batch" else written
        assert written.stat().st_size > 0, command
    assert np.loadtxt(tmp_path / "dots.csv", delimiter=",", skiprows=1).shape == (60, 2)
    assert (tmp_path / "c.csv").read_text().startswith("x,y,layer\n")
