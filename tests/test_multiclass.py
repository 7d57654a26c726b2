"""Colour separation, dots per class, and the joint multi-class objective: sums of independently built terms,
finite-difference derivatives, the union's blue noise, and checkpoints that know the classes."""

import numpy as np
import pytest
from conftest import taylor_slope

from stipple.colour import separate
from stipple.errors import StippleError
from stipple.halftone import run
from stipple.measures.evaluate import discrepancy_energy, expected_iid_energy, torus_clumps
from stipple.multiclass import class_bandwidth, class_counts, halftone_classes, multiclass_problem
from stipple.torus import halftone_torus, torus_problem

STEPS = np.logspace(-3, -4.5, 6)


def test_class_counts_are_the_largest_remainder_rounding():
    assert class_counts([1, 1, 1], 10).tolist() == [4, 3, 3]
    assert class_counts([0.5, 0.3, 0.2], 10).tolist() == [5, 3, 2]
    # quotas 2.4, 3.6, 4.0 -> floors 2, 3, 4 and the one left over goes to the largest remainder (0.6)
    assert class_counts([2.4, 3.6, 4.0], 10).tolist() == [2, 4, 4]
    assert class_counts([0, 3, 1], 7).tolist() == [0, 5, 2]


def test_class_counts_stay_within_one_of_the_quota_and_add_up(rng):
    for _ in range(200):
        masses = rng.random(rng.integers(1, 6)) ** 3
        total = int(rng.integers(1, 10**6))
        counts = class_counts(masses, total)
        quotas = total * masses / masses.sum()
        assert counts.sum() == total and np.all(np.abs(counts - quotas) < 1)


def test_cmyk_separation_reproduces_the_inks_and_takes_grey_into_black(rng):
    rgb = rng.random((5, 7, 3))
    layers = {layer.name: layer.density for layer in separate(rgb, "cmyk")}
    for index, name in enumerate(("cyan", "magenta", "yellow")):
        np.testing.assert_allclose(layers[name] + layers["black"], 1 - rgb[..., index], atol=1e-15)
    np.testing.assert_allclose(layers["black"], (1 - rgb).min(axis=2))
    grey = np.full((4, 4, 3), 0.25)
    assert [layer.name for layer in separate(grey, "cmyk")] == ["black"]
    assert [layer.name for layer in separate(grey, "cmy")] == ["cyan", "magenta", "yellow"]
    with pytest.raises(StippleError, match="blank"):
        separate(np.ones((3, 3, 3)))


def small_problem(rng, hessian="gauss-newton", weights=(1.0, 0.7, 1.3)):
    shape = (10, 14)
    densities = [rng.random(shape), rng.random(shape) ** 2]
    problem = multiclass_problem(densities, 60, 16, term_weights=weights, epsilon=1e-13, hessian=hessian)
    return problem, densities, problem.sample(rng, 60)


def energy_at(objective, points):
    objective.set_points(points)
    return objective.energy()


def test_energy_is_the_weighted_sum_of_independent_class_and_union_problems(rng):
    problem, densities, points = small_problem(rng)
    assert problem.settings["class_points"] == class_counts([d.sum() for d in densities], 60).tolist()
    counts = problem.settings["class_points"]
    bands = [class_bandwidth(16, count, 60) for count in counts]
    assert problem.settings["class_bandwidths"] == bands and bands[0] != bands[1]
    terms = [
        torus_problem(density, count, band, epsilon=1e-13)
        for density, count, band in zip(densities, counts, bands, strict=True)
    ]
    union = torus_problem(densities[0] + densities[1], 60, 16, epsilon=1e-13)
    expected = (
        1.0 * energy_at(terms[0].objective, points[problem.slices[0]])
        + 0.7 * energy_at(terms[1].objective, points[problem.slices[1]])
        + 1.3 * energy_at(union.objective, points)
    )
    assert energy_at(problem.objective, points) == pytest.approx(expected, rel=1e-12)
    # Swapping one dot of each class changes the class terms, not the union term.
    swapped = points.copy()
    swapped[[0, -1]] = swapped[[-1, 0]]
    assert energy_at(problem.objective, swapped) != pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("hessian", ["gauss-newton", "full"])
def test_gradient_and_hessian_taylor_slopes(rng, hessian):
    problem, _, points = small_problem(rng, hessian)
    objective = problem.objective
    energy = energy_at(objective, points)
    gradient = objective.gradient()
    direction = rng.standard_normal(points.shape) * 0.3
    (curved,) = objective.hessian_vectors([direction])
    linear = np.sum(gradient * direction)
    slope = taylor_slope(lambda t: energy_at(objective, points + t * direction) - energy - t * linear, STEPS)
    assert slope == pytest.approx(2, abs=0.1)
    if hessian == "full":
        quadratic = 0.5 * np.sum(direction * curved)

        def remainder(t):
            return energy_at(objective, points + t * direction) - energy - t * linear - t**2 * quadratic

        assert taylor_slope(remainder, STEPS) == pytest.approx(3, abs=0.15)


def test_hessian_gram_is_the_hessian_vectors_inner_products(rng):
    problem, _, points = small_problem(rng)
    objective = problem.objective
    objective.set_points(points)
    fields = [rng.standard_normal(points.shape) for _ in range(2)]
    gram = objective.hessian_gram(fields)
    products = objective.hessian_vectors(fields)
    expected = np.array([[np.sum(u * hv) for hv in products] for u in fields])
    np.testing.assert_allclose(gram, expected, rtol=1e-9)
    assert gram[0, 1] == pytest.approx(gram[1, 0]) and np.all(np.linalg.eigvalsh(gram) > 0)


def test_terms_on_threads_of_their_own_give_the_one_thread_bits(rng):
    """With several threads the terms run at once, each built with one thread: every derivative has the bits of
    the one-thread problem, whatever order the terms finish in."""
    shape = (10, 14)
    densities = [rng.random(shape), rng.random(shape) ** 2, rng.random(shape)]
    single, threaded = (multiclass_problem(densities, 90, 16, threads=count) for count in (1, 3))
    assert threaded.objective.threads == 3 and single.objective.threads == 1
    assert all(term.terms[0].threads == 1 for term in threaded.objective.terms)
    points = single.sample(rng, 90)
    fields = [rng.standard_normal(points.shape) for _ in range(2)]
    results = []
    for problem in (single, threaded, threaded):
        objective = problem.objective
        objective.set_points(points)
        results.append(
            [
                objective.energy(),
                objective.gradient(),
                objective.hessian_gram(fields),
                *objective.hessian_vectors(fields),
            ]
        )
    for threaded_result in results[1:]:
        for mine, theirs in zip(threaded_result, results[0], strict=True):
            np.testing.assert_array_equal(mine, theirs)


def test_joint_classes_are_blue_noise_each_and_together():
    """Two flat classes: optimised jointly, the union has no close pairs; optimised apart, it clumps."""
    flat = np.ones((16, 16))
    problem, joint = halftone_classes([flat, flat], 400, iterations=80)
    apart = np.concatenate([halftone_torus(flat, 200, iterations=80, seed=seed).points for seed in (1, 2)])
    joint_union = torus_clumps(joint.points, 2 * flat)["neighbour_distance_over_hexagonal"]
    apart_union = torus_clumps(apart, 2 * flat)["neighbour_distance_over_hexagonal"]
    assert joint_union["p01"] > 0.6 and apart_union["p01"] < 0.3
    for part, cut in zip(problem.classes, problem.slices, strict=True):
        assert torus_clumps(joint.points[cut], flat)["neighbour_distance_over_hexagonal"]["p01"] > 0.6
        assert discrepancy_energy(part, joint.points[cut]) < 0.05 * expected_iid_energy(part)
    assert np.all(np.diff(joint.energies) <= 1e-12 * joint.energies[0])


def test_resume_continues_exactly_and_refuses_other_classes(rng, tmp_path):
    shape = (12, 12)
    densities = [0.2 + 0.6 * rng.random(shape), 0.2 + 0.6 * rng.random(shape)]
    saved = tmp_path / "run.npz"

    def problem(classes):
        return multiclass_problem(classes, 150, 24, names=["a", "b"])

    whole = run(problem(densities), iterations=12)
    run(problem(densities), iterations=5, checkpoint=saved)
    resumed = run(problem(densities), iterations=12, checkpoint=saved, resume=True)
    np.testing.assert_array_equal(resumed.points, whole.points)
    # The same union and the same class masses, but ink moved from one class to the other pixel by pixel.
    delta = 0.1 * np.where(np.indices(shape).sum(axis=0) % 2 == 0, 1.0, -1.0)
    other = [densities[0] + delta, densities[1] - delta]
    with pytest.raises(StippleError, match="class_fingerprint"):
        run(problem(other), iterations=12, checkpoint=saved, resume=True)
    with pytest.raises(StippleError, match="term_weights"):
        run(
            multiclass_problem(densities, 150, 24, names=["a", "b"], term_weights=[1, 1, 2]),
            iterations=12,
            checkpoint=saved,
            resume=True,
        )
