"""The GPU backend (``stipple.gpu``) without the ``gpu`` extra: one clear line. With a GPU, its transforms against
direct sums (both precisions) are tested in test_transforms.py, its gradient's Taylor slope in test_objective.py and
a run against the CPU's in test_torus.py, each beside the CPU backends' (skipped where there is no GPU, as in CI)."""

import numpy as np
import pytest

from stipple.errors import StippleError
from stipple.nufft import make_nufft


@pytest.fixture
def no_cufinufft(monkeypatch):
    """``import cufinufft`` fails, as where the extra is not installed."""
    import builtins

    real_import = builtins.__import__

    def no_cufinufft(name, *args, **kwargs):
        if name == "cufinufft":
            raise ImportError("No module named 'cufinufft'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_cufinufft)


def test_without_the_extra_the_backend_says_what_is_missing(no_cufinufft):
    with pytest.raises(StippleError, match=r"backend cufinufft needs cufinufft and CuPy.*stipple\[gpu\]"):
        make_nufft("cufinufft", (9, 9), 1e-9, 1)


def test_without_the_extra_the_command_gives_one_line(no_cufinufft, tmp_path):
    from click.testing import CliRunner
    from PIL import Image

    from stipple.cli import main

    Image.fromarray(np.tile(np.arange(0, 240, 10, dtype=np.uint8), (16, 1))).save(tmp_path / "ramp.png")
    output = tmp_path / "dots.csv"
    arguments = ["torus", str(tmp_path / "ramp.png"), "-M", "50", "--backend", "cufinufft", "-q", "-o", str(output)]
    result = CliRunner().invoke(main, arguments)
    assert result.exit_code == 1
    assert "stipple[gpu]" in result.output and "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1
    assert not output.exists()


@pytest.fixture
def failing_cufinufft(monkeypatch):
    """A cufinufft whose plans fail as the library does when the GPU's memory runs out, and a CuPy with one
    device: stand-ins, so that the mapping of the failure is tested without a GPU."""
    import sys
    import types

    def plan(*args, **kwargs):
        raise RuntimeError("Error creating plan.")

    runtime = types.SimpleNamespace(getDeviceCount=lambda: 1, CUDARuntimeError=RuntimeError)
    monkeypatch.setitem(sys.modules, "cufinufft", types.SimpleNamespace(Plan=plan))
    monkeypatch.setitem(sys.modules, "cupy", types.SimpleNamespace(cuda=types.SimpleNamespace(runtime=runtime)))


def test_a_failing_plan_is_one_error_naming_the_grid(failing_cufinufft):
    with pytest.raises(StippleError, match=r"could not make its plans on a 2601 x 1301 mode grid .*out of memory"):
        make_nufft("cufinufft", (2601, 1301), 1e-4, 2)
