"""Spherical designs, checked by direct O(M t^2) sums of scipy's spherical harmonics (independent of the SHTs)
and by the addition theorem (an O(M^2) Legendre sum)."""

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.special import eval_legendre

try:
    from scipy.special import sph_harm_y
except ImportError:  # scipy < 1.15
    from scipy.special import sph_harm

    def sph_harm_y(n, m, theta, phi):
        return sph_harm(m, n, phi, theta)


from stipple.cli import main
from stipple.design import (
    design_points,
    fibonacci_lattice,
    largest_error,
    spherical_design,
    start_points,
)
from stipple.errors import StippleError


def harmonic_errors(points, strength):
    """``max_m |F_nm|``, ``F_nm = (4 pi / M) sum_i Y_nm(x_i)``, for n = 1..t, summed directly."""
    theta = np.arccos(np.clip(points[:, 2], -1, 1))
    phi = np.arctan2(points[:, 1], points[:, 0])
    errors = []
    for degree in range(1, strength + 1):
        orders = np.arange(degree + 1)[:, None]
        values = sph_harm_y(degree, orders, theta[None, :], phi[None, :])
        errors.append(4 * np.pi / len(points) * np.abs(values.sum(axis=1)).max())
    return np.array(errors)


def degree_errors(points, strength):
    """``sqrt(sum_m |F_nm|^2)`` for n = 1..t by the addition theorem:
    ``sum_m |sum_i Y_nm(x_i)|^2 = (2n+1)/(4 pi) sum_ij P_n(x_i . x_j)``, with ``F_nm = (4 pi / M) sum_i Y_nm(x_i)``."""
    cosines = np.clip(points @ points.T, -1, 1)
    count = len(points)
    errors = []
    for degree in range(1, strength + 1):
        total = eval_legendre(degree, cosines).sum() * (2 * degree + 1) / (4 * np.pi)
        errors.append(4 * np.pi / count * np.sqrt(max(total, 0.0)))
    return np.array(errors)


def separation(points):
    """Smallest distance between two points over the hexagonal spacing of their count."""
    cosines = points @ points.T
    np.fill_diagonal(cosines, -1)
    spacing = np.sqrt(8 * np.pi / (np.sqrt(3) * len(points)))
    return np.arccos(np.clip(cosines.max(), -1, 1)) / spacing


def test_default_design_is_a_design_by_the_addition_theorem():
    result = spherical_design(12, threads=1)
    assert result.status == "converged", result.message
    assert len(result.points) == design_points(12) == 93 == int(np.ceil(0.55 * 13**2))
    errors = harmonic_errors(result.points, 12)
    assert errors.max() < 1e-10
    # Not a design of a higher strength: the check can fail.
    assert degree_errors(result.points, 16)[12:].max() > 1e-4
    assert separation(result.points) > 0.3


def test_a_two_thread_design_gives_the_same_bits_every_time():
    """ducc0's adjoint SHT on two threads adds in a scheduling-dependent order: three 2-thread designs of strength
    60 gave three different files. The adjoints run on one thread now."""
    runs = [spherical_design(40, threads=2).points for _ in range(4)]
    for other in runs[1:]:
        np.testing.assert_array_equal(runs[0], other)


def test_largest_error_matches_the_direct_sum_on_a_non_design():
    rng = np.random.default_rng(3)
    result = spherical_design(6, 40, threads=1, iterations=0, init=fibonacci_lattice(40, rng, 0.3))
    from stipple.design import design_problem

    problem = design_problem(6, 40, threads=1)
    problem.discrepancy.set_points(result.points)
    per_degree = np.abs(problem.discrepancy.residual) ** 2 * problem.discrepancy.fourier.multiplicity
    degrees = np.concatenate([np.arange(m, 7) for m in range(7)])
    sums = np.sqrt(np.bincount(degrees, per_degree, minlength=7)[1:])
    np.testing.assert_allclose(sums, degree_errors(result.points, 6), rtol=1e-8)
    np.testing.assert_allclose(np.abs(problem.discrepancy.residual).max(), harmonic_errors(result.points, 6).max())
    assert largest_error(problem.discrepancy) <= sums.max() + 1e-15
    assert largest_error(problem.discrepancy) >= sums.max() / np.sqrt(13)


def test_many_points_start_on_the_lattice_and_stay_separated():
    strength, count = 20, 21**2
    start = start_points(strength, count, "auto", seed=1)
    np.testing.assert_allclose(np.linalg.norm(start, axis=1), 1)
    assert separation(start) > 0.3
    result = spherical_design(strength, count, threads=1, seed=1)
    assert result.status == "converged"
    assert harmonic_errors(result.points, strength).max() < 1e-10
    assert separation(result.points) > 0.3
    assert start_points(strength, design_points(strength), "auto") == "uniform"


def test_sizes_without_a_design_stall_and_say_so():
    """No 6-design has 27 points (Hardin & Sloane): CG stops at a local minimum, which is not called converged."""
    result = spherical_design(6, 27, threads=1)
    assert result.status == "stalled"
    assert "not a design" in result.message
    assert harmonic_errors(result.points, 6).max() > 1e-3
    assert design_points(6) == 28
    assert spherical_design(6, threads=1).status == "converged"


def test_unreachable_target_says_so():
    result = spherical_design(10, 40, threads=1, iterations=30)
    assert result.status == "max_iterations"
    assert "> target 1e-10" in result.message


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"strength": 0}, "strength"),
        ({"strength": 10, "n_points": 5}, "at least"),
        ({"strength": 2, "n_points": 2}, "rounded up: 3"),  # (t+1)^2/4 = 2.25: 2 was let through as "= 2"
        ({"strength": 10, "error": 2.0}, "error"),
        ({"strength": 10, "init": "grid"}, "init"),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(StippleError, match=message):
        spherical_design(**kwargs)


def test_cli_writes_a_full_precision_design_and_resumes(tmp_path):
    out, checkpoint = tmp_path / "d.csv", tmp_path / "d.ckpt"
    base = ["design", "-t", "10", "--threads", "1", "-o", str(out), "--checkpoint", str(checkpoint), "-q"]
    first = CliRunner().invoke(main, base + ["--iterations", "5"])
    assert first.exit_code == 3 and "> target 1e-10" in first.output  # not a design yet: written, and said
    second = CliRunner().invoke(main, base + ["--resume"])
    assert second.exit_code == 0, second.output
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert out.read_text().splitlines()[0] == "x,y,z"
    assert data.shape == (design_points(10), 3)
    assert harmonic_errors(data, 10).max() < 1e-10
    finished = out.read_bytes()
    for _ in range(2):  # a finished design resumed: the same file, no step beyond the target
        again = CliRunner().invoke(main, base + ["--resume"])
        assert again.exit_code == 0 and out.read_bytes() == finished, again.output
    other = CliRunner().invoke(main, [*base[:2], "12", *base[3:], "--resume"])
    assert other.exit_code == 1 and "the map, -M or a design's -t differs" in other.output
    assert out.read_bytes() == finished


def test_cli_measures_the_final_points_accurately_when_epsilon_is_loose(tmp_path):
    """At --epsilon 1e-2 the run's own transforms reported 9.65e-11 <= 1e-10 and exited 0; the points' largest
    error, measured at 1e-12, is about 1e-3: not a design."""
    out = tmp_path / "d.csv"
    result = CliRunner().invoke(main, ["design", "-t", "5", "--epsilon", "1e-2", "--threads", "1", "-o", str(out)])
    assert result.exit_code == 3, result.output
    assert "too loose for the target" in result.output
    assert harmonic_errors(np.loadtxt(out, delimiter=",", skiprows=1), 5).max() > 1e-6


def test_cli_exit_code_says_when_the_points_are_not_a_design(tmp_path):
    """t = 10 has no design of 40 points: the run stalls; a script must tell it from a design (it exited 0)."""
    result = CliRunner().invoke(main, ["design", "-t", "10", "-M", "40", "--threads", "1", "-q", "-o", "-"])
    assert result.exit_code == 3
    assert "not a design" in result.output and "largest error" in result.output


@pytest.mark.parametrize(
    "args, message",
    [
        (["-t", "0"], "strength"),
        (["-t", "10", "--error", "0"], "error"),
        (["-t", "10", "-M", "3"], "at least"),
        (["-t", "10", "--init", "nowhere.csv"], "nowhere.csv"),
    ],
)
def test_cli_bad_input_is_one_line(args, message, tmp_path):
    result = CliRunner().invoke(main, ["design", *args, "-o", str(tmp_path / "d.csv")])
    assert result.exit_code == 1
    assert message in result.output
    assert "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1
    assert not (tmp_path / "d.csv").exists()


def test_the_rounding_floor_is_not_called_a_local_minimum():
    """--error 1e-20 stalls at the rounding floor (6.6e-14 for t = 20): it said "local minimum (not a design)"."""
    floor = CliRunner().invoke(main, ["design", "-t", "20", "--error", "1e-20", "--threads", "1", "-q", "-o", "-"])
    assert floor.exit_code == 3 and "floating-point floor" in floor.output and "local minimum" not in floor.output


def test_a_stall_above_the_gradient_floor_is_found_by_the_energy():
    """t = 3 with 5 points sat at a relative gradient of 1.4e-14, just above the floor, and ran all 20000
    iterations (8 s) before saying it reached them (a held-out review)."""
    result = spherical_design(3, 5, threads=1)
    assert result.status == "stalled" and "local minimum" in result.message and result.iterations < 1000


def test_design_settings_a_caller_gets_wrong_are_named():
    """strength 8192 blamed a count of 36918887 points that no one gave; tol= was a TypeError 'multiple values'
    (a hostile review of the API)."""
    with pytest.raises(StippleError, match="strength 8192 asks for 36918887 points by default"):
        spherical_design(8192)
    with pytest.raises(StippleError, match="a design stops by its error"):
        spherical_design(2, tol=1e-3)


def test_the_callback_sees_the_last_iteration():
    """The error target's stop short-circuited the caller's callback: it never saw the last iteration."""
    seen = []
    result = spherical_design(3, callback=lambda state: seen.append(state.iteration), threads=1)
    assert result.status == "converged" and seen[-1] == result.iterations
