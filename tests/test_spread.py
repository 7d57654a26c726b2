"""The spread step (``stipple.spread``) by its own properties: an exact lattice is left alone, a close pair is
separated while dots away from it stay, every move is bounded, empty pixels keep their dots, and in a run it
raises the low tail of the nearest-neighbour ratio; the same on the sphere, where maps spread and designs do
not."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from stipple.design import fibonacci_lattice
from stipple.halftone import hexagonal_spacing, run
from stipple.manifolds import Sphere
from stipple.measures.evaluate import sphere_clumps, torus_neighbour_ratios
from stipple.sphere import BUILTINS, CellMap, local_density, sphere_problem
from stipple.spread import SPREAD_PASSES, hexagonal_spacing_at, spread_close, spread_close_sphere
from stipple.torus import torus_problem


def square_lattice(k):
    steps = (np.arange(k) + 0.5) / k
    x, y = np.meshgrid(steps, steps)
    return np.stack([x.ravel(), y.ravel()], axis=1)


def periodic_distance(a, b, size):
    delta = (a - b) * size
    delta -= size * np.rint(delta / size)
    return np.linalg.norm(delta, axis=-1)


def test_hexagonal_spacing_is_that_of_the_pixel_density():
    weights = np.ones((8, 8))
    weights[:, 4:] = 3.0
    points = np.array([[0.1, 0.5], [0.9, 0.5], [0.6, 0.1]])
    density = len(points) * np.array([1.0, 3.0, 3.0]) / weights.sum()
    assert np.allclose(hexagonal_spacing_at(points, weights), np.sqrt(2 / (np.sqrt(3) * density)))
    weights[:, 4:] = 0.0
    assert np.isinf(hexagonal_spacing_at(points, weights)[1:]).all()


def test_a_lattice_above_the_target_is_left_exactly_alone():
    # A square lattice's ratio is sqrt(sqrt(3) / 2) = 0.93 everywhere: above the target, nothing moves.
    points = square_lattice(16)
    spread, moved = spread_close(points, np.ones((64, 64)), target=0.9)
    assert moved == 0
    assert np.array_equal(spread, points)


def test_a_close_pair_is_separated_and_dots_away_from_it_stay():
    k, pixels = 16, 64
    lattice = square_lattice(k)
    extra = lattice[100] + np.array([0.2, 0.1]) / k
    points = np.vstack([lattice, extra])
    weights = np.ones((pixels, pixels))
    size = np.array([pixels, pixels], dtype=float)
    spread, moved = spread_close(points, weights)
    assert moved >= 2
    before = periodic_distance(points[100], points[-1], size)
    after = periodic_distance(spread[100], spread[-1], size)
    assert after > before + 0.5 * (0.78 * hexagonal_spacing_at(points, weights)[0] - before)
    # The smallest nearest-neighbour distance of the whole set grows.
    nearest = [cKDTree(p * size, boxsize=size).query(p * size, k=2)[0][:, 1].min() for p in (points, spread)]
    assert nearest[1] > nearest[0]
    # Dots more than three lattice spacings from the pair never move (each pass reaches one neighbour further).
    far = periodic_distance(points, extra, size) > 3 * pixels / k
    assert np.array_equal(spread[far], points[far])


def test_moves_are_bounded_and_empty_pixels_keep_their_dots(rng):
    weights = rng.random((40, 60)) + 0.2
    weights[:10, :] = 0.0
    points = rng.random((3000, 2))
    spread, moved = spread_close(points, weights, target=0.85)
    assert moved > 0
    assert np.all((spread >= 0) & (spread < 1))
    size = np.array(weights.shape[::-1], dtype=float)
    shift = periodic_distance(spread, points, size)
    spacing = hexagonal_spacing_at(points, weights)
    empty = np.isinf(spacing)
    assert empty.any() and np.all(shift[empty] < 1e-12)
    # A pass moves a dot by at most half the target spacing (its neighbour at distance 0 at the worst).
    assert np.all(shift[~empty] <= SPREAD_PASSES * 0.85 * spacing[~empty] / 2 + 1e-9)
    # Fewer dots below the target afterwards (i.i.d. points: most are below it, three passes fix some), and the
    # low tail rises.
    ratio_before = torus_neighbour_ratios(points, weights)[~empty]
    ratio_after = torus_neighbour_ratios(spread, weights)[~empty]
    assert np.sum(ratio_after < 0.85) < 0.9 * np.sum(ratio_before < 0.85)
    assert np.percentile(ratio_after, 5) > np.percentile(ratio_before, 5) + 0.1


@pytest.fixture(scope="module")
def small_runs():
    yy, xx = np.mgrid[0:48, 0:48] / 48
    weights = 0.15 + np.where((xx - 0.5) ** 2 + (yy - 0.5) ** 2 < 0.09, 0.85, 0.2 * xx)
    problem = torus_problem(weights, 3000)
    return weights, problem, {flag: run(problem, seed=0, iterations=40, spread=flag) for flag in (False, True)}


def test_spread_in_a_run_raises_the_ratio_tail_at_nearly_the_same_energy(small_runs):
    weights, problem, results = small_runs
    plain, spread = results[False], results[True]
    assert "close dots spread" in spread.message and "spread" not in plain.message
    assert spread.iterations == plain.iterations
    tails = [np.percentile(torus_neighbour_ratios(r.points, weights), 1) for r in (plain, spread)]
    assert tails[1] > tails[0]
    problem.objective.set_points(plain.points)
    plain_energy = problem.objective.energy()
    problem.objective.set_points(spread.points)
    assert problem.objective.energy() < 1.01 * plain_energy


# The sphere: the same step along great circles (``spread_close_sphere``).


def geodesic(a, b):
    return 2 * np.arcsin(np.minimum(np.linalg.norm(a - b, axis=-1) / 2, 1.0))


def uniform_local_density(count):
    return np.full(count, count / (4 * np.pi))


def test_sphere_a_fibonacci_lattice_above_the_target_is_left_exactly_alone():
    points = fibonacci_lattice(2000)
    ratios = sphere_clumps(points, BUILTINS["uniform"])["neighbour_distance_over_hexagonal"]
    target = 0.95 * ratios["min"]
    spread, moved = spread_close_sphere(points, uniform_local_density(len(points)), target=target)
    assert moved == 0
    assert np.array_equal(spread, points)


def test_dots_on_top_of_each_other_are_separated():
    """Two dots at the same point have no direction away from each other: each moves its own way (torus)."""
    lattice = square_lattice(16)
    points = np.vstack([lattice, lattice[100]])
    weights = np.ones((64, 64))
    spread, moved = spread_close(points, weights)
    assert moved >= 2
    assert periodic_distance(spread[100], spread[-1], np.array([64.0, 64.0])) > 0.5 * 0.78 * 4


def test_sphere_a_close_pair_is_separated_and_dots_away_from_it_stay():
    lattice = fibonacci_lattice(2000)
    spacing = hexagonal_spacing(len(lattice) / (4 * np.pi), 1.0)
    # A dot a fifth of a spacing from lattice dot 700, along the meridian.
    tangent = np.cross(lattice[700], [0.0, 0.0, 1.0])
    tangent /= np.linalg.norm(tangent)
    extra = np.cos(0.2 * spacing) * lattice[700] + np.sin(0.2 * spacing) * tangent
    points = np.vstack([lattice, extra])
    # Below every ratio of the lattice itself (its dots near the poles are less regular than 0.78).
    target = 0.95 * sphere_clumps(lattice, BUILTINS["uniform"])["neighbour_distance_over_hexagonal"]["min"]
    spread, moved = spread_close_sphere(points, uniform_local_density(len(points)), target=target)
    assert moved >= 2
    assert np.allclose(np.linalg.norm(spread, axis=1), 1.0, atol=1e-14)
    before, after = geodesic(points[700], points[-1]), geodesic(spread[700], spread[-1])
    assert after > before + 0.5 * (target * spacing - before)
    nearest = [cKDTree(p).query(p, k=2)[0][:, 1].min() for p in (points, spread)]
    assert nearest[1] > nearest[0]
    far = geodesic(points, extra) > 3 * spacing
    assert np.array_equal(spread[far], points[far])


def test_sphere_dots_on_top_of_each_other_are_separated():
    lattice = fibonacci_lattice(2000)
    points = np.vstack([lattice, lattice[700]])
    spacing = hexagonal_spacing(len(lattice) / (4 * np.pi), 1.0)
    spread, _ = spread_close_sphere(points, uniform_local_density(len(points)), target=0.5)
    assert np.allclose(np.linalg.norm(spread, axis=1), 1.0, atol=1e-14)
    assert geodesic(spread[700], spread[-1]) > 0.2 * spacing


def test_sphere_moves_are_bounded_and_empty_cells_keep_their_dots(rng):
    values = rng.random((30, 60)) + 0.2
    values[:8] = 0.0
    density = CellMap(values)
    points = Sphere().random(rng, 3000)
    local = local_density(density, points)
    spread, moved = spread_close_sphere(points, local, target=0.85)
    assert moved > 0
    assert np.allclose(np.linalg.norm(spread, axis=1), 1.0, atol=1e-14)
    shift = geodesic(spread, points)
    empty = local == 0
    spacing = hexagonal_spacing(local[~empty], 1.0)
    assert empty.any() and np.all(shift[empty] == 0)
    assert np.all(shift[~empty] <= SPREAD_PASSES * 0.85 * spacing / 2 + 1e-9)
    tails = [sphere_clumps(p, density)["neighbour_distance_over_hexagonal"]["p05"] for p in (points, spread)]
    assert tails[1] > tails[0] + 0.1


def test_sphere_maps_spread_in_a_run_and_designs_do_not():
    yy, xx = np.mgrid[0:40, 0:80] / 40
    values = 0.2 + np.where(np.abs(yy - 0.5) < 0.15, 0.8, 0.3 * xx)
    problem = sphere_problem(values, 3000, threads=2)
    assert sphere_problem(BUILTINS["uniform"], 200, threads=2).spread is None
    results = {flag: run(problem, seed=0, iterations=40, spread=flag) for flag in (False, True)}
    plain, spread = results[False], results[True]
    assert "close dots spread" in spread.message and spread.iterations == plain.iterations
    density = CellMap(values)
    tails = [sphere_clumps(r.points, density)["neighbour_distance_over_hexagonal"]["p01"] for r in (plain, spread)]
    assert tails[1] > tails[0]
    energies = []
    for result in (plain, spread):
        problem.objective.set_points(result.points)
        energies.append(problem.objective.energy())
    assert energies[1] < 1.01 * energies[0]


def test_a_dot_on_a_faint_fringe_moves_no_farther_than_its_dense_neighbour_allows():
    """A dot whose own spacing is tens of degrees (a faint fringe beside a dense blob) counted as close to its
    neighbour in the blob and was thrown half that spacing away, up to 82 degrees into an empty region."""
    lattice = fibonacci_lattice(2000)
    dense = len(lattice) / (4 * np.pi)
    spacing = hexagonal_spacing(dense, 1.0)
    tangent = np.cross(lattice[700], [0.0, 0.0, 1.0])
    tangent /= np.linalg.norm(tangent)
    fringe = np.cos(0.5 * spacing) * lattice[700] + np.sin(0.5 * spacing) * tangent
    points = np.vstack([lattice, fringe])
    density = np.append(np.full(len(lattice), dense), 1e-3)  # the fringe's own spacing: about 3 radians
    spread, _ = spread_close_sphere(points, density, target=0.78)
    assert geodesic(spread[-1], fringe) <= SPREAD_PASSES * 0.5 * 0.78 * spacing


def test_the_spread_step_gives_the_same_bits_on_any_number_of_threads(rng):
    """The nearest-neighbour queries run on the problem's threads: every query is its own, so the moves do not
    depend on the count (the torus and the sphere)."""
    weights = rng.random((40, 60)) + 0.2
    points = rng.random((5000, 2))
    one, moved = spread_close(points, weights, target=0.85)
    assert moved > 0
    for threads in (2, 3):
        assert np.array_equal(spread_close(points, weights, target=0.85, threads=threads)[0], one)
    vectors = Sphere().random(rng, 5000)
    local = local_density(CellMap(rng.random((30, 60)) + 0.2), vectors)
    one = spread_close_sphere(vectors, local, target=0.85)[0]
    assert np.array_equal(spread_close_sphere(vectors, local, target=0.85, threads=2)[0], one)


def test_problems_spread_on_their_threads(monkeypatch):
    """``torus_problem`` and ``sphere_problem`` hand their thread count to the spread step."""
    import stipple.sphere
    import stipple.torus

    seen = []

    def recorded(function):
        return lambda *args, **kwargs: seen.append(kwargs["threads"]) or function(*args, **kwargs)

    monkeypatch.setattr(stipple.torus, "spread_close", recorded(spread_close))
    monkeypatch.setattr(stipple.sphere, "spread_close_sphere", recorded(spread_close_sphere))
    rng = np.random.default_rng(0)
    torus_problem(np.ones((16, 16)), 100, threads=3).spread(rng.random((100, 2)))
    sphere_problem(np.ones((20, 40)) + np.eye(20, 40), 100, threads=3).spread(Sphere().random(rng, 100))
    assert seen == [3, 3]
