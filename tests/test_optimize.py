"""The CG driver on a small objective with known behaviour (independent of the transforms)."""

import numpy as np
import pytest

from stipple.manifolds import PinnedTorus, ScaledTorus, Sphere, Torus
from stipple.optimize import BETAS, minimize


class Bowl:
    """``E = sum (p - c)^4`` on the torus (no wrap-around near c), with a curvature form scaled by ``trust``.

    ``trust < 1`` underestimates the curvature, so Newton steps overshoot and the energy can rise.
    """

    def __init__(self, centre, trust=1.0):
        self.centre, self.trust = centre, trust

    def set_points(self, points):
        self.offset = points - self.centre

    def energy(self):
        return float(np.sum(self.offset**4))

    def gradient(self):
        return 4 * self.offset**3

    def hessian_gram(self, vectors):
        curvature = self.trust * 12 * self.offset**2
        return np.array([[np.sum(u * curvature * v) for v in vectors] for u in vectors])


def test_cg_converges_on_a_bowl():
    centre = np.full((5, 2), 0.5)
    start = centre + np.linspace(-0.2, 0.2, 10).reshape(5, 2)
    result = minimize(Bowl(centre), Torus(), start, tol=1e-6, max_iterations=500)
    assert result.status == "converged"
    np.testing.assert_allclose(result.points, centre, atol=1e-2)
    assert np.all(np.diff(result.energies) <= 0)


def test_safeguard_stops_energy_rises():
    centre = np.full((5, 2), 0.5)
    start = centre + np.linspace(-0.2, 0.2, 10).reshape(5, 2)
    # Daniel's rule: with it this start overshoots (Hestenes-Stiefel's happens not to).
    options = {"tol": 1e-12, "max_iterations": 60, "beta": "daniel"}
    plain = minimize(Bowl(centre, trust=0.3), Torus(), start, **options)
    guarded = minimize(Bowl(centre, trust=0.3), Torus(), start, safeguard=True, **options)
    assert np.any(np.diff(plain.energies) > 0)
    assert np.all(np.diff(guarded.energies) <= 1e-12 * guarded.energies[:-1])
    assert guarded.energies[-1] < 1e-3 * guarded.energies[0]


def test_time_limit_and_callback_stop():
    centre = np.full((5, 2), 0.5)
    start = centre + 0.1
    assert minimize(Bowl(centre), Torus(), start, tol=1e-15, max_iterations=10**6, time_limit=1e-9).status == (
        "time_limit"
    )
    calls = []
    result = minimize(Bowl(centre), Torus(), start, tol=1e-15, callback=lambda s: calls.append(s) or len(calls) > 3)
    assert result.status == "stopped" and result.iterations == 3


def test_riemannian_cg_on_the_sphere_minimises_height():
    """``E = sum z_i`` on (S²)^M: every point runs to the south pole."""

    class Height:
        def set_points(self, points):
            self.points = points

        def energy(self):
            return float(np.sum(self.points[:, 2]))

        def gradient(self):
            return np.tile([0.0, 0.0, 1.0], (len(self.points), 1))

        def hessian_gram(self, vectors):
            # Riemannian Hessian of the height function: -z <u, v> per point.
            weights = -self.points[:, 2:3]
            return np.array([[np.sum(weights * u * v) + 1e-3 * np.sum(u * v) for v in vectors] for u in vectors])

    rng = np.random.default_rng(3)
    start = Sphere().random(rng, 20)
    start[:, 2] = -np.abs(start[:, 2]) - 0.1
    start /= np.linalg.norm(start, axis=1, keepdims=True)
    result = minimize(Height(), Sphere(), start, tol=1e-8, max_iterations=200, safeguard=True)
    np.testing.assert_allclose(result.points[:, 2], -1, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(result.points, axis=1), 1, atol=1e-14)


def test_zero_gradient_start_is_converged():
    centre = np.full((3, 2), 0.5)
    result = minimize(Bowl(centre), Torus(), centre.copy(), tol=1e-3)
    assert result.status == "converged" and result.iterations == 0


class Quadratic:
    """``E = (p - c)^T A (p - c) / 2`` over the flattened points, ``A`` symmetric positive definite."""

    def __init__(self, centre, matrix):
        self.centre, self.matrix = centre, matrix

    def set_points(self, points):
        self.offset = (points - self.centre).ravel()

    def energy(self):
        return 0.5 * float(self.offset @ self.matrix @ self.offset)

    def gradient(self):
        return (self.matrix @ self.offset).reshape(self.centre.shape)

    def hessian_gram(self, vectors):
        flat = [v.ravel() for v in vectors]
        return np.array([[u @ self.matrix @ v for v in flat] for u in flat])


@pytest.mark.parametrize("beta", BETAS)
def test_cg_ends_on_a_quadratic_in_as_many_steps_as_dimensions(beta):
    """Exact line search on a quadratic: CG is exact after n = 8 steps, and both beta rules take the same ones."""
    rng = np.random.default_rng(5)
    factor = rng.standard_normal((8, 8))
    matrix = factor @ factor.T + 0.5 * np.eye(8)
    centre = np.full((4, 2), 0.5)
    start = centre + 0.05 * rng.standard_normal((4, 2))
    paths = {}
    for rule in BETAS:
        paths[rule] = []
        minimize(
            Quadratic(centre, matrix),
            Torus(),
            start,
            tol=1e-300,
            max_iterations=8,
            beta=rule,
            callback=lambda state, path=paths[rule]: path.append(state.points.copy()),
        )
    np.testing.assert_allclose(paths[beta][-1], centre, atol=1e-11)
    for mine, theirs in zip(paths[beta], paths["daniel"], strict=True):
        np.testing.assert_allclose(mine, theirs, atol=1e-11)


@pytest.mark.parametrize("beta", BETAS)
def test_both_beta_rules_descend_on_a_bowl(beta):
    centre = np.full((5, 2), 0.5)
    start = centre + np.linspace(-0.2, 0.2, 10).reshape(5, 2)
    result = minimize(Bowl(centre), Torus(), start, tol=1e-6, max_iterations=500, beta=beta)
    assert result.status == "converged"
    assert np.all(np.diff(result.energies) <= 0)


def test_a_pinned_torus_keeps_its_base_metric_and_moves_only_the_free_points():
    rng = np.random.default_rng(3)
    points, covector, direction = rng.random((3, 50, 2))
    field = 0.5 + rng.random((12, 16))
    base = ScaledTorus((1.0, 0.75), field)
    free = rng.random(50) < 0.4
    pinned = PinnedTorus(base, free)
    assert pinned.inner(points, covector, direction) == base.inner(points, covector, direction)
    moved = pinned.riesz(points, covector)
    np.testing.assert_array_equal(moved[free], base.riesz(points, covector)[free])
    assert not moved[~free].any() and not pinned.transport(points, moved, direction)[~free].any()
    np.testing.assert_array_equal(pinned.retract(points, moved)[~free], points[~free])
