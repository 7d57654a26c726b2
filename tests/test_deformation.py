"""Smooth deformations of a point set (``stipple.deformation``): the field against direct sums, the adjoint, the
derivatives in the coefficients, and a smooth distortion of a lattice undone."""

import numpy as np
import pytest
from conftest import energy_at, taylor_slope

from stipple.deformation import Deformation, DeformationSpace, DeformedObjective, deform
from stipple.torus import torus_problem
from stipple.transforms import torus_modes

STEPS = np.logspace(-2.5, -4, 6)
BANDWIDTHS = (8, 6)


def random_coeffs(rng, deformation, size=1.0):
    return size * rng.standard_normal(deformation.zero().size)


def test_the_field_is_the_real_part_of_its_fourier_series_summed_directly(rng):
    points = rng.random((50, 2))
    deformation = Deformation(points, BANDWIDTHS)
    coeffs = random_coeffs(rng, deformation)
    grids = coeffs.view(np.complex128).reshape(deformation.shape)
    n1, n2 = torus_modes(deformation.shape[1:])
    waves = np.exp(2j * np.pi * (np.multiply.outer(points[:, 0], n1) + np.multiply.outer(points[:, 1], n2)))
    direct = np.stack([np.einsum("mab,ab->m", waves, grid).real for grid in grids], axis=1)
    np.testing.assert_allclose(deformation.displacement(coeffs), direct, atol=1e-8 * np.abs(direct).max())


def test_the_constant_mode_translates_every_dot():
    points = np.random.default_rng(1).random((30, 2))
    deformation = Deformation(points, BANDWIDTHS)
    grids = np.zeros(deformation.shape, dtype=np.complex128)
    centre = tuple(n // 2 for n in BANDWIDTHS)
    grids[(0, *centre)], grids[(1, *centre)] = 0.25, -0.125
    moved = deformation.points(grids.view(np.float64).reshape(-1))
    np.testing.assert_allclose(moved, np.mod(points + [0.25, -0.125], 1.0), atol=1e-12)


def test_pullback_is_the_adjoint_of_the_displacement(rng):
    points = rng.random((40, 2))
    deformation = Deformation(points, BANDWIDTHS)
    coeffs, covector = random_coeffs(rng, deformation), rng.standard_normal(points.shape)
    left = np.dot(deformation.pullback(covector), coeffs)
    right = np.sum(covector * deformation.displacement(coeffs))
    assert left == pytest.approx(right, rel=1e-9)


def test_riesz_represents_a_differential_in_the_metric(rng):
    deformation = Deformation(rng.random((10, 2)), BANDWIDTHS)
    space = DeformationSpace((1.0, 0.6), deformation)
    covector, vector = random_coeffs(rng, deformation), random_coeffs(rng, deformation)
    assert space.inner(None, space.riesz(None, covector), vector) == pytest.approx(np.dot(covector, vector))


def deformed_problem(rng, hessian):
    weights = 0.2 + rng.random((12, 20))
    problem = torus_problem(weights, 40, 16, threads=1, epsilon=1e-13, hessian=hessian, precondition=False)
    points = problem.sample(rng, 40)
    return DeformedObjective(problem.objective, Deformation(points, BANDWIDTHS))


def first_order(objective, rng):
    """``(start, direction, energy, linear term)`` at no displacement, along a random direction."""
    start = objective.deformation.zero()
    direction = random_coeffs(rng, objective.deformation, 0.01)
    objective.set_points(start)
    return start, direction, objective.energy(), np.dot(objective.gradient(), direction)


def test_gradient_in_the_coefficients_has_taylor_slope_two(rng):
    objective = deformed_problem(rng, "gauss-newton")
    start, direction, energy, linear = first_order(objective, rng)
    remainder = lambda t: energy_at(objective, start + t * direction) - energy - t * linear  # noqa: E731
    assert taylor_slope(remainder, STEPS) == pytest.approx(2, abs=0.1)


def test_full_hessian_form_in_the_coefficients_has_taylor_slope_three(rng):
    objective = deformed_problem(rng, "full")
    start, direction, energy, linear = first_order(objective, rng)
    quadratic = 0.5 * objective.hessian_gram([direction])[0, 0]

    def remainder(t):
        return energy_at(objective, start + t * direction) - energy - t * linear - t**2 * quadratic

    assert taylor_slope(remainder, STEPS) == pytest.approx(3, abs=0.15)


def test_a_smooth_distortion_of_a_lattice_is_undone():
    # E_N of a 16 x 16 lattice for the constant density is 0 below its size (N = 24): every mode but 0 sums to
    # zero over it. Its columns and rows squeezed by a field of one wave, it is not (shifting whole rows along
    # themselves would be invisible); ten steps over fields of that bandwidth bring the dots back to the lattice.
    side = 16
    lattice = (np.stack(np.meshgrid(np.arange(side), np.arange(side), indexing="ij"), -1).reshape(-1, 2) + 0.5) / side
    bend = 0.3 / side * np.stack([np.sin(2 * np.pi * lattice[:, 0]), np.cos(2 * np.pi * lattice[:, 1])], axis=1)
    problem = torus_problem(np.ones((32, 32)), side**2, 24, threads=1, epsilon=1e-12, near_field=False)
    bent = np.mod(lattice + bend, 1.0)
    energy = lambda points: energy_at(problem.objective, points)  # noqa: E731
    assert energy(lattice) < 1e-20 < 1e-10 < energy(bent)
    points, result = deform(problem.objective, problem.manifold.scale, bent, 4, 10)
    assert energy(points) < 1e-5 * energy(bent)
    offsets = np.mod(points - lattice + 0.5 / side, 1.0 / side) - 0.5 / side
    assert np.abs(offsets - offsets.mean(axis=0)).max() < 0.01 / side and result.iterations <= 10
