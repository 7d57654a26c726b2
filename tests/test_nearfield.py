"""The near-field split: kernels against closed forms and transforms, pair sums against direct O(M²) sums,
derivatives against finite differences, and repulsion below the bandwidth's resolution."""

import numpy as np
import pytest
from conftest import energy_at, gradient_taylor_slope, hessian_taylor_slope, taylor_slope
from scipy.special import j0, roots_legendre

from stipple.halftone import run
from stipple.kernels import NearKernel, ball_kernel, ball_profile, chord_profile
from stipple.manifolds import Sphere
from stipple.nearfield import NearField, SpherePairs, TorusPairs
from stipple.sphere import sphere_problem
from stipple.torus import torus_problem

STEPS = np.logspace(-3, -4.5, 6)


def hankel(function, radius, frequency, nodes=4000):
    """``2 pi int_0^radius f(r) J0(2 pi rho r) r dr`` by brute-force Gauss-Legendre."""
    x, w = roots_legendre(nodes)
    r, w = (x + 1) * radius / 2, w * radius / 2
    return 2 * np.pi * np.sum(w * function(r) * j0(2 * np.pi * frequency * r) * r)


def test_ball_profile_is_the_space_form_of_the_ball_kernel():
    for frequency in (0.0, 0.7, 3.0, 25.0):
        transform = hankel(lambda r: ball_profile(np.maximum(r, 1e-300))[0], 1.0, frequency)
        assert transform == pytest.approx(ball_kernel(np.array([frequency]))[0], rel=1e-9, abs=1e-15)


def test_ball_profile_derivatives_match_finite_differences():
    d, h = np.array([0.01, 0.2, 0.6]), 1e-6
    values = ball_profile(d)
    for order in range(4):
        difference = (ball_profile(d + h)[order] - ball_profile(d - h)[order]) / (2 * h)
        np.testing.assert_allclose(difference, values[order + 1], rtol=1e-6)


@pytest.mark.parametrize("profile", [ball_profile, chord_profile])
def test_near_kernel_vanishes_smoothly_at_its_radius(profile):
    kernel = NearKernel(profile, 0.05)
    inside = kernel.values(np.array([0.05 * (1 - 1e-9)]))
    assert np.allclose(inside, 0, atol=1e-9)
    r, h = np.array([0.004, 0.02, 0.045]), 1e-7
    value, slope, curvature = kernel.values(r)
    np.testing.assert_allclose((kernel.values(r + h)[0] - kernel.values(r - h)[0]) / (2 * h), slope, rtol=1e-6)
    np.testing.assert_allclose((kernel.values(r + h)[1] - kernel.values(r - h)[1]) / (2 * h), curvature, rtol=1e-5)


def test_plane_coefficients_match_brute_force_quadrature():
    kernel = NearKernel(ball_profile, 0.01)
    frequencies = np.array([0.0, 40.0, 150.0, 300.0])
    expected = [hankel(lambda r: kernel.values(r)[0], 0.01, f) for f in frequencies]
    np.testing.assert_allclose(kernel.plane_coefficients(frequencies), expected, rtol=1e-9)


def test_sphere_coefficients_match_brute_force_quadrature():
    """``k_n = 2 pi int K_near(2 sin(theta/2)) P_n(cos theta) sin(theta) dtheta`` over the cap of the radius."""
    from scipy.special import eval_legendre

    kernel = NearKernel(chord_profile, 0.4)
    coeffs = kernel.sphere_coefficients(300)
    x, w = roots_legendre(4000)
    top = 2 * np.arcsin(0.2)
    theta, w = (x + 1) * top / 2, w * top / 2
    integrand = kernel.values(2 * np.sin(theta / 2))[0] * np.sin(theta) * w
    for n in (0, 1, 7, 80, 300):
        expected = 2 * np.pi * np.sum(integrand * eval_legendre(n, np.cos(theta)))
        assert coeffs[n] == pytest.approx(expected, rel=1e-9, abs=1e-14)


def separated_points(rng, count, dimension=2):
    """Jittered points no two of which are closer than a fifth of the mean spacing (cusps stay out of reach)."""
    while True:
        points = rng.random((count, dimension)) if dimension == 2 else Sphere().random(rng, count)
        if dimension == 2:
            delta = points[:, None] - points[None]
            delta -= np.round(delta)
        else:
            delta = points[:, None] - points[None]
        distance = np.sqrt((delta**2).sum(-1)) + np.eye(count)
        if distance.min() > 0.2 / np.sqrt(count):
            return points


def direct_torus_energy(points, scale, weight):
    """``lam² sum_ij K(p_i - p_j)`` of the whole periodised ball kernel (uniform density), and its differential."""
    x = points * scale
    total, gradient = 0.0, np.zeros_like(x)
    for shift in np.ndindex(7, 7):
        delta = x[:, None] - x[None] + (np.array(shift) - 3) * scale
        r = np.sqrt((delta**2).sum(-1))
        inside = r < 1
        value, slope = ball_profile(np.where(inside, np.maximum(r, 1e-300), 0.5))[:2]
        total += np.sum(np.where(inside, value, 0.0))
        gradient += 2 * np.sum(np.where(inside & (r > 0), slope / np.maximum(r, 1e-300), 0.0)[..., None] * delta, 1)
    energy = weight**2 * (scale[0] * scale[1] * total - len(x) ** 2 * ball_kernel(np.zeros(1))[0])
    return energy, weight**2 * scale[0] * scale[1] * gradient * scale


@pytest.mark.parametrize("shape", [(30, 30), (20, 50)])
def test_torus_split_equals_the_direct_sum_of_the_whole_kernel(rng, shape):
    points = rng.random((50, 2))
    errors = {}
    for near_field in (True, False):
        problem = torus_problem(np.ones(shape), 50, 128, epsilon=1e-13, near_field=near_field)
        problem.objective.set_points(points)
        energy, gradient = direct_torus_energy(points, problem.manifold.scale, problem.discrepancy.weight)
        errors[near_field] = (
            abs(problem.objective.energy() / energy - 1),
            np.abs(problem.objective.gradient() - gradient).max() / np.abs(gradient).max(),
        )
    assert errors[True][0] < 1e-5 and errors[True][1] < 1e-3
    # Without the near field the truncated kernel misses the cusp: errors at least 30 times larger.
    assert errors[False][0] > 30 * errors[True][0] and errors[False][1] > 10 * errors[True][1]


def test_sphere_split_equals_the_direct_sum_of_the_distance_kernel(rng):
    """Uniform density: the untruncated energy is ``lam² sum_ij (4/3 - |x_i - x_j|)``."""
    points = Sphere().random(rng, 80)
    problem = sphere_problem(None, 80, 96, kernel="distance", threads=1, epsilon=1e-13, near_field=True)
    problem.objective.set_points(points)
    chords = np.linalg.norm(points[:, None] - points[None], axis=-1)
    weight = problem.discrepancy.weight
    energy = weight**2 * np.sum(4 / 3 - chords)
    differential = -2 * weight**2 * np.sum((points[:, None] - points[None]) / (chords + np.eye(80))[..., None], 1)
    gradient = Sphere().project(points, differential)
    assert problem.objective.energy() == pytest.approx(energy, rel=1e-5)
    found = Sphere().project(points, problem.objective.gradient())
    assert np.abs(found - gradient).max() < 2e-3 * np.abs(gradient).max()


def brute_force_pairs(kernel, positions, scale=None):
    delta = positions[:, None] - positions[None]
    if scale is not None:
        delta -= scale * np.round(delta / scale)
    return np.sum(kernel.values(np.sqrt((delta**2).sum(-1)))[0])


def test_pair_sums_match_all_pairs_also_after_moves(rng):
    """The Verlet list must find every pair within the radius, before and after points move."""
    scale = np.array([1.0, 0.4])
    kernel = NearKernel(ball_profile, 0.06)
    field = NearField(kernel, weight=0.5, geometry=TorusPairs(scale), factor=0.4)
    points = rng.random((400, 2))
    for step in range(8):
        field.set_points(points)
        expected = 0.25 * 0.4 * brute_force_pairs(kernel, np.mod(points, 1) * scale, scale)
        assert field.energy() == pytest.approx(expected, rel=1e-12)
        points = points + 0.0015 * rng.standard_normal(points.shape)
        # A few points jump anywhere: they are looked up on their own, the list is kept.
        points[rng.choice(400, 3, replace=False)] = rng.random((3, 2))
        if step == 6:
            points[:40] = rng.random((40, 2))  # too many movers: a new search
    assert 1 < field.counts["pair_searches"] < 6


def test_many_movers_are_patched_with_the_pairs_among_them(rng):
    """Up to 1 % of the points may move far between searches (300 of 30000 here, many of them close together):
    the patched list must hold exactly the pairs a fresh search finds, in the same order."""
    kernel = NearKernel(ball_profile, 0.004)
    field = NearField(kernel, weight=1.0, geometry=TorusPairs(np.ones(2)))
    fresh = NearField(kernel, weight=1.0, geometry=TorusPairs(np.ones(2)))
    points = rng.random((30000, 2))
    field.set_points(points)
    movers = rng.choice(30000, 300, replace=False)
    points = points.copy()
    points[movers] = 0.5 + 0.02 * rng.random((300, 2))  # a dense cluster: many mover-mover pairs
    field.set_points(points)
    fresh.set_points(points)
    assert field.counts["pair_searches"] == 1
    for mine, theirs in zip(field.pairs(), fresh.pairs(), strict=True):
        np.testing.assert_array_equal(mine, theirs)
    assert field.pair_count > 1000
    assert field.energy() == fresh.energy()


def test_sphere_pair_sums_match_all_pairs(rng):
    kernel = NearKernel(chord_profile, 0.2)
    field = NearField(kernel, weight=1.0, geometry=SpherePairs())
    points = Sphere().random(rng, 300)
    field.set_points(points)
    assert field.energy() == pytest.approx(brute_force_pairs(kernel, points), rel=1e-12)


def near_torus_problem(rng, hessian="gauss-newton"):
    weights = rng.random((12, 20)) + 0.2
    problem = torus_problem(weights, 40, 16, threads=1, epsilon=1e-13, hessian=hessian)
    return problem, separated_points(rng, 40)


def test_torus_gradient_taylor_slope_two_with_near_field(rng):
    problem, points = near_torus_problem(rng)
    objective = problem.objective
    assert objective.terms[1].kernel.radius > 0.1  # the pairs really take part
    direction = rng.standard_normal(points.shape)
    assert gradient_taylor_slope(objective, points, direction, STEPS) == pytest.approx(2, abs=0.1)


def test_torus_full_hessian_taylor_slope_three_with_near_field(rng):
    problem, points = near_torus_problem(rng, hessian="full")
    objective = problem.objective
    direction = rng.standard_normal(points.shape)
    slope, hess_direction = hessian_taylor_slope(objective, points, direction, STEPS)
    assert objective.hessian_gram([direction])[0, 0] == pytest.approx(np.sum(direction * hess_direction), rel=1e-9)
    assert slope == pytest.approx(3, abs=0.15)


def test_gauss_newton_stand_in_is_positive_and_symmetric(rng):
    problem, points = near_torus_problem(rng)
    near = problem.objective.terms[1]
    near.set_points(points)
    vectors = list(rng.standard_normal((3,) + points.shape))
    gram = near.hessian_gram(vectors)
    products = near.hessian_vectors(vectors)
    expected = np.array([[np.sum(u * hv) for hv in products] for u in vectors])
    np.testing.assert_allclose(gram, expected, rtol=1e-10)
    assert np.all(np.linalg.eigvalsh(gram) > 0)


def test_sphere_gradient_and_exact_hessian_along_geodesics(rng):
    """Riemannian Taylor slopes of the near field alone: 2 for the gradient, 3 with the exact Hessian."""
    manifold = Sphere()
    points = separated_points(rng, 60, dimension=3)
    field = NearField(NearKernel(chord_profile, 0.6), weight=0.1, geometry=SpherePairs(), hessian="full")
    field.set_points(points)
    energy = field.energy()
    gradient = manifold.riesz(points, field.gradient())
    direction = manifold.project(points, rng.standard_normal(points.shape))
    curvature = field.hessian_gram([direction])[0, 0]

    def remainder(t, order):
        moved = energy_at(field, manifold.retract(points, t * direction)) - energy
        return moved - t * manifold.inner(points, gradient, direction) - (order == 3) * 0.5 * t**2 * curvature

    assert taylor_slope(lambda t: remainder(t, 2), STEPS) == pytest.approx(2, abs=0.1)
    assert taylor_slope(lambda t: remainder(t, 3), STEPS) == pytest.approx(3, abs=0.15)


def test_sphere_objective_gradient_taylor_slope_two_with_near_field(rng):
    problem = sphere_problem(rng.random((6, 12)) + 0.3, 40, 12, threads=1, epsilon=1e-13)
    objective, manifold = problem.objective, problem.manifold
    points = separated_points(rng, 40, dimension=3)
    objective.set_points(points)
    energy, gradient = objective.energy(), manifold.riesz(points, objective.gradient())
    direction = manifold.project(points, rng.standard_normal(points.shape))

    def remainder(t):
        return (
            energy_at(objective, manifold.retract(points, t * direction))
            - energy
            - t * manifold.inner(points, gradient, direction)
        )

    assert taylor_slope(remainder, STEPS) == pytest.approx(2, abs=0.1)


def clumped_lattice(k):
    """A k×k lattice with every point doubled at a tenth of the spacing: 2 k² points."""
    grid = (np.arange(k) + 0.5) / k
    lattice = np.stack(np.meshgrid(grid, grid, indexing="ij"), axis=-1).reshape(-1, 2)
    return np.concatenate([lattice, lattice + [0.1 / k, 0.0]])


def minimum_distance(points):
    delta = points[:, None] - points[None]
    delta -= np.round(delta)
    return (np.sqrt((delta**2).sum(-1)) + np.eye(len(points))).min()


@pytest.mark.parametrize("near_field", [True, False])
def test_pairs_closer_than_the_bandwidth_resolves_are_pushed_apart(near_field):
    """Doubled lattice points at 0.1/k with N/2 < k: the near field separates them, the truncated kernel cannot."""
    k = 14
    points = clumped_lattice(k)
    problem = torus_problem(np.ones((8, 8)), len(points), 12, threads=1, epsilon=1e-12, near_field=near_field)
    # The objective alone: the spread step (stipple.spread) would separate the pairs either way.
    result = run(problem, init=points, tol=1e-10, iterations=60, spread=False)
    spacing = 1 / (k * np.sqrt(2))  # hexagonal-ish spacing of 2 k² points
    if near_field:
        assert minimum_distance(result.points) > 0.5 * spacing
    else:
        assert minimum_distance(result.points) < 0.2 * spacing


def test_resume_with_the_near_field_is_bit_identical(rng, tmp_path):
    """The pair sums must not depend on where the Verlet list was last searched (a resumed run searches anew)."""
    weights = 0.2 + 0.6 * rng.random((12, 12))
    saved = tmp_path / "run.npz"
    whole = run(torus_problem(weights, 150, 24), iterations=12)
    run(torus_problem(weights, 150, 24), iterations=5, checkpoint=saved)
    resumed = run(torus_problem(weights, 150, 24), iterations=12, checkpoint=saved, resume=True)
    np.testing.assert_array_equal(resumed.points, whole.points)


@pytest.mark.parametrize("available, refused", [(0.5, True), (4.0, False)])
def test_clumped_points_are_refused_before_their_pairs_fill_the_memory(monkeypatch, available, refused):
    """4000 coincident points have n (n - 1) / 2 = 8.0 million pairs (about 1.1 GiB of candidates), which the
    estimate from a sample finds exactly; 40000 of them (800 million pairs) ended ``stipple evaluate`` by the
    kernel's OOM killer (a hostile review). Refused where they would not fit, one error naming the count."""
    import stipple.allocator
    from stipple.errors import StippleError
    from stipple.nearfield import check_pair_memory

    monkeypatch.setattr(stipple.allocator, "available_memory", lambda: available * 2**30)
    points = np.full((4000, 2), 0.25)
    tree = TorusPairs(np.ones(2)).tree(points)
    if refused:
        with pytest.raises(StippleError, match=r"clumped: about 8e\+06 pairs .* 1\.1 GiB, more than the 0\.5 GiB"):
            check_pair_memory(tree, points, 0.01)
    else:
        check_pair_memory(tree, points, 0.01)
    spread = np.random.default_rng(0).random((4000, 2))  # about 1.3 neighbours each within 0.01: a few kB
    monkeypatch.setattr(stipple.allocator, "available_memory", lambda: 2**20)
    check_pair_memory(TorusPairs(np.ones(2)).tree(spread), spread, 0.01)


def test_a_clump_between_the_sampled_points_is_found(monkeypatch):
    """An evenly spaced sample of 1000 points missed a clump of contiguous rows shorter than its spacing (a code
    review); one point in PAIR_SAMPLE_EVERY is sampled where that is more (here 50, for a clump of 100 rows)."""
    import stipple.allocator
    import stipple.nearfield
    from stipple.errors import StippleError
    from stipple.nearfield import check_pair_memory

    points = np.random.default_rng(0).random((200_100, 2))
    points[50:150] = 0.25  # between the 1000-point sample's rows 0 and 200: 4950 pairs, about 0.7 MB
    monkeypatch.setattr(stipple.allocator, "available_memory", lambda: 0.5 * 2**20)
    monkeypatch.setattr(stipple.nearfield, "PAIR_SAMPLE_EVERY", 50)
    tree = TorusPairs(np.ones(2)).tree(points)
    with pytest.raises(StippleError, match="the points are clumped"):
        check_pair_memory(tree, points, 1e-4)
