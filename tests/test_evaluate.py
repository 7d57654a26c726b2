import numpy as np
import pytest
from click.testing import CliRunner

from stipple.cli import main
from stipple.evaluate import (
    cap_discrepancy,
    discrepancy_energy,
    evaluate_sphere,
    evaluate_torus,
    expected_iid_energy,
    fibonacci_sphere,
    minimum_separation,
    power_spectrum,
    psnr,
    ssim,
    torus_neighbour_ratios,
)
from stipple.sphere import BUILTINS, CellMap, sphere_problem, three_gaussians
from stipple.torus import torus_problem


def lattice(k):
    grid = (np.arange(k) + 0.5) / k
    return np.stack(np.meshgrid(grid, grid, indexing="ij"), axis=-1).reshape(-1, 2)


def test_expected_energy_of_iid_samples_torus(rng):
    weights = np.outer(np.linspace(0.2, 1, 10), np.linspace(1, 0.3, 14))
    problem = torus_problem(weights, 200, 16, threads=1)
    expected = expected_iid_energy(problem)
    energies = [discrepancy_energy(problem, problem.sample(rng, 200)) for _ in range(1000)]
    assert np.mean(energies) == pytest.approx(expected, rel=0.05)


def test_expected_energy_of_iid_samples_sphere(rng):
    density = BUILTINS["gaussians"]
    problem = sphere_problem(density, 150, 12, threads=1)
    expected = expected_iid_energy(problem)
    energies = []
    cells = CellMap(density.cell_map().values)
    for _ in range(1000):
        energies.append(discrepancy_energy(problem, cells.sample(rng, 150)))
    assert np.mean(energies) == pytest.approx(expected, rel=0.05)


def test_lattice_measures():
    points = lattice(12)
    flat = np.ones((12, 12))
    report = evaluate_torus(torus_problem(flat, 144, 22, threads=1, epsilon=1e-13), points, flat)
    assert report["energy"] < 1e-25 and report["flat_input"]
    # Square lattice spacing 1/k against hexagonal sqrt(2/(sqrt(3) M)): ratio (3/4)^(1/4) for every point.
    np.testing.assert_allclose(torus_neighbour_ratios(points, flat), (3 / 4) ** 0.25, rtol=1e-12)
    for item in report["similarity"]:
        assert item["psnr"] == float("inf") and item["ssim"] == pytest.approx(1.0)


def test_lattice_power_spectrum_peaks_at_its_frequency():
    points = lattice(10)
    spectrum = power_spectrum(torus_problem(np.ones((8, 8)), 100, 30, threads=1, epsilon=1e-13), points)
    power = dict(zip(spectrum["frequency"], spectrum["power"], strict=True))
    assert power[10] > 1 and max(power[f] for f in range(1, 10)) < 1e-18


def test_ssim_and_psnr_basics(rng):
    image = rng.random((20, 30))
    assert ssim(image, image) == pytest.approx(1.0)
    assert psnr(image, image) == float("inf")
    noisy = image + 0.1 * rng.standard_normal(image.shape)
    assert ssim(image, noisy) < ssim(image, image + 0.01 * rng.standard_normal(image.shape)) < 1
    assert psnr(image, noisy) == pytest.approx(10 * np.log10(image.max() ** 2 / 0.01), abs=0.3)


def test_sphere_measures_on_a_design():
    octahedron = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    report = evaluate_sphere(sphere_problem(None, 6, 3, threads=1, epsilon=1e-13), octahedron, BUILTINS["uniform"])
    assert report["max_coefficient_error"] < 1e-13 and report["energy"] < 1e-25
    assert report["minimum_separation_degrees"] == pytest.approx(90)


def test_cap_discrepancy_known_cases(rng):
    cells = CellMap(np.ones((90, 180)))
    centres, masses = cells.centres_and_masses()
    north = fibonacci_sphere(2000)
    north[:, 2] = np.abs(north[:, 2])
    assert cap_discrepancy(north, centres, masses) == pytest.approx(0.5, abs=0.02)
    spread, random = fibonacci_sphere(2000), rng.standard_normal((2000, 3))
    random /= np.linalg.norm(random, axis=1, keepdims=True)
    assert cap_discrepancy(spread, centres, masses) < 0.5 * cap_discrepancy(random, centres, masses)
    assert minimum_separation(spread) > 3 * minimum_separation(random)


def test_evaluate_cli_our_points_beat_iid_on_the_portrait(tmp_path):
    from pathlib import Path

    portrait = Path(__file__).resolve().parents[1] / "samples" / "astronaut256.png"
    runner = CliRunner()
    ours = tmp_path / "ours.csv"
    iid = tmp_path / "iid.csv"
    common = ["torus", str(portrait), "-M", "4000", "-q", "--threads", "2"]
    assert runner.invoke(main, common + ["--iterations", "150", "-o", str(ours)]).exit_code == 0
    assert runner.invoke(main, common + ["--iterations", "0", "-o", str(iid)]).exit_code == 0
    import json

    reports = []
    for points in (ours, iid):
        result = runner.invoke(main, ["evaluate", str(points), str(portrait), "--json", "-"])
        assert result.exit_code == 0, result.output
        reports.append(json.loads(result.stdout))
    assert reports[0]["energy_ratio_to_iid"] < 0.1 < reports[1]["energy_ratio_to_iid"]
    for mine, theirs in zip(reports[0]["similarity"], reports[1]["similarity"], strict=True):
        assert mine["psnr"] > theirs["psnr"] + 3
    assert (
        reports[0]["neighbour_distance_over_hexagonal"]["p05"]
        > 2 * reports[1]["neighbour_distance_over_hexagonal"]["p05"]
    )


def test_evaluate_cli_sphere_and_spectrum(tmp_path):
    runner = CliRunner()
    points = tmp_path / "dots.csv"
    result = runner.invoke(
        main, ["sphere", "builtin:gaussians", "-M", "300", "-N", "16", "--iterations", "30", "-q", "-o", str(points)]
    )
    assert result.exit_code == 0
    result = runner.invoke(main, ["evaluate", str(points), "builtin:gaussians", "-N", "16"])
    assert result.exit_code == 0 and "cap discrepancy" in result.output and "ratio to i.i.d." in result.output
    flat = tmp_path / "flat.npy"
    np.save(flat, np.array([[0.0, 1.0], [1.0, 1.0]]))


def test_three_gaussians_positive():
    assert np.all(three_gaussians(fibonacci_sphere(100)) > 0)
