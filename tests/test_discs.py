"""Discs optimised with their positions (``stipple.discs``): transforms, derivatives, an exact case, a run."""

import numpy as np
import pytest
from conftest import gradient_taylor_slope
from scipy.special import j0, j1

from stipple import StippleError
from stipple.discs.problem import DiscFactors, disc_factor, disc_problem, optimise_discs, tone_radius
from stipple.transforms import torus_modes

STEPS = np.logspace(-2.5, -4, 6)


def small_problem(rng, backend="ducc0", count=25, shape=(12, 20), bandwidth=14):
    """A rectangular image, discs of radii 0.5-1.6 times the tone radius at random places: ``(problem, x)``."""
    weights = rng.random(shape)
    problem = disc_problem(weights, count, bandwidth, backend=backend, threads=1, epsilon=1e-12)
    radii = problem.tone_radius * rng.uniform(0.5, 1.6, count)
    return problem, problem.pack(rng.random((count, 2)), radii)


def direct_jacobian(problem, points):
    """``mu_n`` and ``d mu_n / d(x_i, y_i, s_i)`` by direct sums with ``scipy.special`` (modes x M x 3)."""
    objective = problem.objective
    n1, n2 = torus_modes(objective.nufft.shape)
    scale = problem.scale
    frequency = np.hypot(n1 / scale[0], n2 / scale[1])[..., None]
    area = np.exp(points[:, 2])
    radii = np.sqrt(area / np.pi)
    z = 2 * np.pi * frequency * radii
    phi = np.where(z == 0, 1.0, 2 * j1(z) / np.where(z == 0, 1.0, z))
    phases = np.exp(-2j * np.pi * (n1[..., None] * points[:, 0] + n2[..., None] * points[:, 1])) / np.prod(scale)
    coefficients = np.sum(area * phi * phases, axis=-1)
    jacobian = np.stack(
        [
            area * phi * (-2j * np.pi * n1[..., None]) * phases,
            area * phi * (-2j * np.pi * n2[..., None]) * phases,
            area * j0(z) * phases,
        ],
        axis=-1,
    )
    return coefficients, jacobian


@pytest.mark.parametrize("backend", ["ducc0", "finufft"])
def test_fast_coefficients_match_the_direct_sum(rng, backend):
    problem, points = small_problem(rng, backend)
    problem.objective.set_points(points)
    direct, _ = direct_jacobian(problem, points)
    error = np.max(np.abs(problem.objective.coefficients - direct)) / np.max(np.abs(direct))
    assert error < 1e-10
    assert 4 <= problem.objective.factors.rank <= 12


def test_split_transforms_give_the_same_coefficients(rng):
    """Two threads on a grid of >= 64 rows take ``ResidueSplitNufft``; the result is the one-thread one."""
    weights = rng.random((16, 16))
    results = []
    for threads in (1, 2):
        problem = disc_problem(weights, 40, 80, threads=threads, epsilon=1e-12)
        problem.objective.set_points(problem.pack(np.random.default_rng(5).random((40, 2)), problem.tone_radius))
        results.append((problem.objective.coefficients.copy(), problem.objective.gradient()))
    assert np.allclose(results[0][0], results[1][0], rtol=0, atol=1e-12 * np.max(np.abs(results[0][0])))
    assert np.allclose(results[0][1], results[1][1], rtol=0, atol=1e-10 * np.max(np.abs(results[0][1])))


def test_factors_are_accurate_beyond_the_fitted_samples():
    factors = DiscFactors(max_frequency=140.0, max_radius=0.015, tolerance=1e-8)
    frequency = np.random.default_rng(1).uniform(0, 140, 300)
    u = np.random.default_rng(2).uniform(0, 0.015**2, 200)
    alpha, _ = factors.sizes(u)
    approximate = factors.radial(frequency) @ alpha.T
    assert np.max(np.abs(approximate - disc_factor(frequency, u))) < 1e-8 * np.pi * 0.015**2


@pytest.mark.parametrize("backend", ["ducc0", "finufft"])
@pytest.mark.parametrize("moved", [slice(0, 2), slice(2, 3), slice(0, 3)], ids=["positions", "sizes", "both"])
def test_gradient_taylor_slope_two_in_positions_and_sizes(rng, backend, moved):
    problem, points = small_problem(rng, backend)
    direction = np.zeros(points.shape)
    direction[:, moved] = rng.standard_normal((len(points), moved.stop - moved.start))
    assert gradient_taylor_slope(problem.objective, points, direction, STEPS) == pytest.approx(2, abs=0.1)


def test_gradient_matches_the_direct_jacobian(rng):
    problem, points = small_problem(rng)
    objective = problem.objective
    objective.set_points(points)
    coefficients, jacobian = direct_jacobian(problem, points)
    residual = coefficients - objective.target
    expected = 2 * np.einsum("ij,ijmc->mc", objective.kernel, (jacobian.conj() * residual[..., None, None]).real)
    assert np.allclose(objective.gradient(), expected, rtol=0, atol=1e-9 * np.max(np.abs(expected)))


def test_gauss_newton_forms_match_the_direct_jacobian(rng):
    problem, points = small_problem(rng)
    objective = problem.objective
    objective.set_points(points)
    _, jacobian = direct_jacobian(problem, points)
    fields = [rng.standard_normal(points.shape) for _ in range(2)]
    products = [np.einsum("ijmc,mc->ij", jacobian, v) for v in fields]
    for fast, direct in zip(objective.jacobian(fields), products, strict=True):
        assert np.max(np.abs(fast - direct)) < 1e-10 * np.max(np.abs(direct))
    kernel = objective.kernel
    gram = [[2 * np.sum(kernel * (a.conj() * b).real) for b in products] for a in products]
    assert np.allclose(objective.hessian_gram(fields), gram, rtol=1e-9)
    weighted = kernel * products[0]
    expected = 2 * np.sum((jacobian.conj() * weighted[..., None, None]).real, axis=(0, 1))
    (fast,) = objective.hessian_vectors(fields[:1])
    assert np.allclose(fast, expected, rtol=0, atol=1e-9 * np.max(np.abs(expected)))
    assert np.sum(fields[0] * fast) == pytest.approx(gram[0][0], rel=1e-9)


def test_lattice_on_a_constant_image_wants_the_tone_area(rng):
    """A k x k lattice of equal discs on a constant image: only the mass term is left for N/2 < k."""
    shade, side = 0.4, 8
    weights = np.full((32, 32), shade)
    count = side * side
    problem = disc_problem(weights, count, 6, threads=1, epsilon=1e-12)
    grid = (np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2) + rng.random(2)) / side
    right = tone_radius(weights, count)
    assert np.pi * right**2 * count == pytest.approx(shade)
    energies, gradients = {}, {}
    for factor in (0.8, 1.0, 1.2):
        points = problem.pack(np.mod(grid, 1.0), np.full(count, np.sqrt(factor) * right))
        problem.objective.set_points(points)
        energies[factor], gradients[factor] = problem.objective.energy(), problem.objective.gradient()
    assert energies[1.0] < 1e-12 * min(energies[0.8], energies[1.2])
    assert energies[0.8] == pytest.approx(problem.mass_weight * (0.2 * shade) ** 2, rel=1e-9)
    assert np.max(np.abs(gradients[1.0])) < 1e-9 * np.max(np.abs(gradients[0.8][:, 2]))
    assert np.all(gradients[0.8][:, 2] < 0) and np.all(gradients[1.2][:, 2] > 0)


def test_optimise_discs_lowers_the_energy(rng):
    y, x = np.mgrid[0:24, 0:32] / 24
    weights = 0.2 + 0.6 * x / x.max() + 0.1 * np.sin(6 * y)
    result = optimise_discs(weights, 150, iterations=15, threads=1, settle=0, seed=3)
    assert result.energies[-1] < 0.7 * result.energies[0]
    assert result.points.shape == (150, 2) and result.radii.shape == (150,)
    assert np.all((result.points >= 0) & (result.points < 1)) and np.all(result.radii > 0)
    assert result.iterations == 15 and result.status == "max_iterations" and result.seconds > 0
    held = optimise_discs(weights, result.points, result.radii, iterations=3, threads=1, sizes=False)
    assert np.allclose(held.radii, result.radii) and held.energies[-1] <= held.energies[0]


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (dict(radii=-1.0), "radii must be in"),
        (dict(radii=np.ones(3) * 0.01), "radii must be a number or an array of shape"),
        (dict(points=np.zeros((5, 3))), "points must be a finite"),
        (dict(backend="nfft"), "backend must be one of"),
        (dict(mass_weight=-1.0), "mass_weight must be"),
        (dict(iterations=-1), "iterations must be"),
        (dict(bandwidth=7), "bandwidth must be an even integer"),
    ],
)
def test_bad_settings_name_the_parameter(options, message):
    weights = np.full((8, 8), 0.5)
    arguments = dict(points=np.full((5, 2), 0.5), radii=None) | options
    with pytest.raises(StippleError, match=message):
        optimise_discs(weights, arguments.pop("points"), arguments.pop("radii"), threads=1, **arguments)
