"""Row blocks on threads (``stipple.parallel``): the same sums as one piece, the same bits on every run."""

import numpy as np
import pytest
from test_nearfield import brute_force_pairs

import stipple.parallel
from stipple.kernels import NearKernel, ball_profile
from stipple.nearfield import NearField, TorusPairs
from stipple.parallel import map_blocks, row_blocks, sum_blocks
from stipple.torus import torus_problem


@pytest.mark.parametrize("rows", [0, 1, 5, 97, 1000])
@pytest.mark.parametrize("threads", [1, 2, 3, 8])
def test_row_blocks_cover_every_row_once(monkeypatch, rows, threads):
    monkeypatch.setattr(stipple.parallel, "MIN_BLOCK_SIZE", 10)
    array = np.zeros((rows, 7))
    blocks = row_blocks(array, threads)
    covered = np.concatenate([np.arange(rows)[block] for block in blocks])
    assert np.array_equal(covered, np.arange(rows))
    assert len(blocks) == max(1, min(threads, rows, rows * 7 // 10))
    sizes = [block.stop - block.start for block in blocks]
    assert max(sizes) - min(sizes) <= 1


def test_small_arrays_stay_in_one_piece():
    assert len(row_blocks(np.zeros((100, 100)), 8)) == 1
    assert len(row_blocks(np.zeros((1000, 1000)), 8)) == 8


def test_blocks_compute_what_one_piece_computes(monkeypatch, rng):
    monkeypatch.setattr(stipple.parallel, "MIN_BLOCK_SIZE", 100)
    first, second = rng.standard_normal((2, 301, 50))
    out = np.empty_like(first)
    map_blocks(3, np.multiply, first, second, out)
    assert np.array_equal(out, first * second)
    total = sum_blocks(3, lambda a, b: np.einsum("ij,ij->", a, b), first, second)
    assert total == pytest.approx(np.sum(first * second), rel=1e-13)


def threaded_problem(threads, rng_seed=0):
    rng = np.random.default_rng(rng_seed)
    weights = rng.random((40, 60)) + 0.1
    return torus_problem(weights, 1500, 128, threads=threads, epsilon=1e-12), rng.random((1500, 2))


def test_threaded_objective_equals_single_threaded_and_repeats_its_bits(monkeypatch):
    """Blocks small enough that the mode grids and the pairs are split: energy, gradient and Hessian forms agree
    with one thread to rounding, and two evaluations give the same bits."""
    monkeypatch.setattr(stipple.parallel, "MIN_BLOCK_SIZE", 256)
    single, points = threaded_problem(1)
    threaded, _ = threaded_problem(3)
    direction = np.random.default_rng(1).standard_normal(points.shape)
    results = []
    for problem in (single, threaded, threaded):
        objective = problem.objective
        objective.set_points(points)
        results.append((objective.energy(), objective.gradient(), objective.hessian_gram([direction, points])))
    discrepancy, pairs = threaded.objective.terms
    assert len(row_blocks(discrepancy.residual, 3)) == 3
    assert len(row_blocks(pairs._candidates[0], 3)) == 3 and pairs.pair_count > 1000
    (energy, gradient, gram), (energy3, gradient3, gram3), repeated = results
    assert energy3 == pytest.approx(energy, rel=1e-12)
    assert np.abs(gradient3 - gradient).max() < 1e-10 * np.abs(gradient).max()
    assert np.allclose(gram3, gram, rtol=1e-10, atol=0)
    assert repeated[0] == energy3 and np.array_equal(repeated[1], gradient3) and np.array_equal(repeated[2], gram3)


def test_pair_blocks_match_all_pairs_and_one_block(monkeypatch, rng):
    monkeypatch.setattr(stipple.parallel, "MIN_BLOCK_SIZE", 50)
    scale = np.array([1.0, 0.5])
    kernel = NearKernel(ball_profile, 0.08)
    fields = [NearField(kernel, weight=0.5, geometry=TorusPairs(scale), factor=0.5, threads=t) for t in (1, 4)]
    points = rng.random((300, 2))
    direction = rng.standard_normal(points.shape)
    for field in fields:
        field.set_points(points)
    single, threaded = fields
    assert len(row_blocks(threaded._candidates[0], 4)) == 4
    expected = 0.25 * 0.5 * brute_force_pairs(kernel, points * scale, scale)
    assert threaded.energy() == pytest.approx(expected, rel=1e-12)
    assert np.allclose(threaded.gradient(), single.gradient(), rtol=1e-12, atol=1e-15 * np.abs(single.gradient()).max())
    assert threaded.hessian_gram([direction])[0, 0] == pytest.approx(single.hessian_gram([direction])[0, 0], rel=1e-12)
    (product,), (expected_product,) = threaded.hessian_vectors([direction]), single.hessian_vectors([direction])
    assert np.allclose(product, expected_product, rtol=1e-12, atol=1e-15 * np.abs(expected_product).max())
    assert np.array_equal(np.sort(threaded.pairs()[0]), np.sort(single.pairs()[0]))


def test_transforms_and_pairs_at_once_give_the_bits_of_one_after_the_other():
    """Two threads: the transforms and the pairs run at once, one thread each, and every derivative has the bits
    of the one-thread problem, which evaluates them one after the other."""
    single, points = threaded_problem(1)
    both, _ = threaded_problem(2)
    assert both.objective.concurrent and not single.objective.concurrent
    assert [term.threads for term in both.objective.terms] == [1, 1]
    fields = [np.random.default_rng(2).standard_normal(points.shape), points]
    results = []
    for problem in (single, both):
        objective = problem.objective
        objective.set_points(points)
        evaluations = [objective.energy(), objective.gradient(), objective.hessian_gram(fields)]
        results.append(evaluations + objective.hessian_vectors(fields))
    for mine, theirs in zip(*results, strict=True):
        np.testing.assert_array_equal(mine, theirs)


def test_a_large_grid_gives_the_derivatives_the_pairs_thread_and_repeats_its_bits(monkeypatch):
    """Above ``SHARED_DERIVATIVE_ROWS`` rows the gradient's and the Hessian form's transforms take both threads
    (the residual keeps one beside the pairs): the energy has the bits of one thread, the derivatives agree with
    them to rounding, and two evaluations give the same bits."""
    import stipple.torus

    monkeypatch.setattr(stipple.torus, "SHARED_DERIVATIVE_ROWS", 64)
    single, points = threaded_problem(1)
    shared, _ = threaded_problem(2)
    fourier = shared.objective.terms[0].fourier
    assert fourier.nufft.shape[0] > 64 and fourier.nufft.threads == 2
    assert fourier.half_nufft.threads == 1 and fourier.threads == 1
    fields = [np.random.default_rng(2).standard_normal(points.shape), points]
    results = []
    for problem in (single, shared, shared):
        objective = problem.objective
        objective.set_points(points)
        evaluations = [objective.energy(), objective.gradient(), objective.hessian_gram(fields)]
        results.append(evaluations + objective.hessian_vectors(fields))
    one, two, again = results
    assert two[0] == one[0]
    for mine, theirs in zip(two[1:], one[1:], strict=True):
        assert np.abs(mine - theirs).max() <= 1e-10 * np.abs(theirs).max()
    for mine, theirs in zip(again, two, strict=True):
        np.testing.assert_array_equal(mine, theirs)
