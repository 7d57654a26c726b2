"""The GPU backend (``stipple.gpu``): its transforms against direct sums, its derivatives by their Taylor slope, a
run against the CPU's; without the ``gpu`` extra, one clear line. Its tests skip where no GPU is (CI)."""

import numpy as np
import pytest
from conftest import gradient_taylor_slope, needs_gpu
from test_transforms import direct_matrix

from stipple.errors import StippleError
from stipple.torus import halftone_torus, torus_problem
from stipple.transforms import make_nufft


@needs_gpu
@pytest.mark.parametrize("epsilon", [1e-12, 1e-4])
def test_transforms_against_direct_sums(epsilon, rng):
    """Double precision to 1e-9; single precision (epsilon 1e-4) to the libraries' bound, relative to the sums of
    magnitudes; half-widths odd and even, points outside [0, 1)."""
    shape = (21, 15)
    points = rng.random((300, 2)) * 3 - 1
    nufft = make_nufft("cufinufft", shape, epsilon, 2)
    nufft.set_points(points)
    matrix = direct_matrix(points, shape)
    values = rng.standard_normal((2, 300)) + 1j * rng.standard_normal((2, 300))
    coeffs = rng.standard_normal((2,) + shape) + 1j * rng.standard_normal((2,) + shape)
    forward, backward = nufft.type1(values), nufft.type2(coeffs)
    assert forward.dtype == backward.dtype == np.complex128
    tolerance = max(epsilon, 1e-11)
    forward_error = np.abs(forward - np.einsum("bm,mxy->bxy", values, matrix)).max()
    backward_error = np.abs(backward - np.einsum("bxy,mxy->bm", coeffs, matrix.conj())).max()
    assert forward_error < tolerance * np.abs(values).sum(axis=1).max()
    assert backward_error < tolerance * np.abs(coeffs).sum(axis=(1, 2)).max()
    assert nufft.counts == {"type1": 2, "type2": 2, "set_points": 1}


@needs_gpu
def test_gradient_taylor_slope_two(rng):
    problem = torus_problem(
        rng.random((12, 20)), 30, 14, threads=1, epsilon=1e-13, backend="cufinufft", near_field=False
    )
    points = problem.sample(rng, 30)
    direction = rng.standard_normal(points.shape)
    assert gradient_taylor_slope(problem.objective, points, direction, np.logspace(-2.5, -4, 6)) == pytest.approx(
        2, abs=0.1
    )


@needs_gpu
def test_a_run_reaches_the_cpu_runs_energies():
    weights = np.outer(np.linspace(0.1, 1, 16), np.ones(16))
    energies = [
        halftone_torus(weights, 200, 30, iterations=15, tol=1e-12, threads=1, backend=backend, epsilon=1e-11).energies
        for backend in ("ducc0", "cufinufft")
    ]
    np.testing.assert_allclose(energies[0], energies[1], rtol=1e-6)


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
