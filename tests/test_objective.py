"""Derivatives of the discrepancy against finite differences and exact adjoint identities."""

import numpy as np
import pytest
from conftest import backend_params, gradient_taylor_slope, hessian_taylor_slope

from stipple.manifolds import Torus
from stipple.nufft import BACKENDS
from stipple.torus import torus_problem

STEPS = np.logspace(-2.5, -4, 6)


def small_problem(rng, shape=(12, 20), hessian="gauss-newton", backend="ducc0"):
    weights = rng.random(shape)
    problem = torus_problem(
        weights, 30, 14, threads=1, epsilon=1e-13, hessian=hessian, backend=backend, near_field=False
    )
    return problem, problem.sample(rng, 30)


@pytest.mark.parametrize("backend", backend_params(BACKENDS))
def test_gradient_taylor_slope_two(rng, backend):
    problem, points = small_problem(rng, backend=backend)
    objective = problem.objective
    direction = rng.standard_normal(points.shape)
    assert gradient_taylor_slope(objective, points, direction, STEPS) == pytest.approx(2, abs=0.1)


def test_full_hessian_taylor_slope_three(rng):
    problem, points = small_problem(rng, hessian="full")
    objective = problem.objective
    direction = rng.standard_normal(points.shape)
    slope, _ = hessian_taylor_slope(objective, points, direction, STEPS)
    assert slope == pytest.approx(3, abs=0.15)


def test_gauss_newton_is_two_jt_k_j_with_finite_difference_jacobian(rng):
    problem, points = small_problem(rng)
    objective = problem.objective
    direction = rng.standard_normal(points.shape)
    objective.set_points(points)
    residual = objective._residual.copy()
    (hess_direction,) = objective.hessian_vectors([direction])
    t = 1e-6
    objective.set_points(points + t * direction)
    jacobian_direction = (objective._residual - residual) / t
    quadratic = 2 * np.sum(objective.energy_weights * np.abs(jacobian_direction) ** 2)
    assert np.sum(direction * hess_direction) == pytest.approx(quadratic, rel=1e-5)


def test_gradient_synthesis_is_adjoint_of_gradient_analysis(rng):
    problem, points = small_problem(rng)
    fourier = problem.objective.fourier
    fourier.set_points(points)
    vectors = rng.standard_normal(points.shape)
    coeffs = fourier.analysis() * problem.objective.kernel  # Hermitian
    left = np.sum(vectors * fourier.gradient_synthesis([coeffs])[0])
    right = np.real(np.sum(np.conj(coeffs) * fourier.gradient_analysis([vectors])[0]))
    assert left == pytest.approx(right, rel=1e-10)


def test_hessian_is_symmetric(rng):
    problem, points = small_problem(rng, hessian="full")
    objective = problem.objective
    objective.set_points(points)
    u, v = rng.standard_normal((2,) + points.shape)
    hu, hv = objective.hessian_vectors([u, v])
    assert np.sum(v * hu) == pytest.approx(np.sum(u * hv), rel=1e-9)


def test_rectangular_metric_gradient_is_riesz_representer(rng):
    manifold = Torus((1.0, 0.6))
    covector = rng.standard_normal((5, 2))
    vector = rng.standard_normal((5, 2))
    assert manifold.inner(None, manifold.riesz(None, covector), vector) == pytest.approx(np.sum(covector * vector))


@pytest.mark.parametrize("hessian", ["gauss-newton", "full"])
def test_hessian_gram_matches_hessian_vectors(rng, hessian):
    problem, points = small_problem(rng, hessian=hessian)
    objective = problem.objective
    objective.set_points(points)
    u, v = rng.standard_normal((2,) + points.shape)
    gram = objective.hessian_gram([u, v])
    hu, hv = objective.hessian_vectors([u, v])
    expected = np.array([[np.sum(u * hu), np.sum(u * hv)], [np.sum(v * hu), np.sum(v * hv)]])
    np.testing.assert_allclose(gram, expected, rtol=1e-9)
