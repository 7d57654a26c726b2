import numpy as np
import pytest
from conftest import assert_derivatives_alike, backend_params
from scipy.special import roots_legendre

from stipple import torus_spectrum
from stipple.errors import StippleError
from stipple.halftone import COARSE_LEVELS, DEFAULT_SETTLE, run
from stipple.nufft import BACKENDS
from stipple.optimize import SETTLE_WINDOW
from stipple.peaks import peak_ratio
from stipple.sampling import MIN_BLOCK_LEVEL, _cells_at, _cells_through_blocks, hilbert_index, stratified_cells
from stipple.torus import (
    DEFAULT_EPSILON,
    DERIVATIVE_EPSILON,
    derivative_accuracy,
    halftone_torus,
    sample_image,
    stratified_sample,
    torus_problem,
)
from stipple.torus_spectrum import (
    CACHED_MODES,
    PixelDensity,
    axis_bandwidths,
    image_coefficients,
    radial_on_modes,
    torus_kernel,
    torus_kernels,
    torus_near_kernel,
    torus_scale,
)
from stipple.transforms import torus_modes


def brute_force_coefficients(weights, bandwidths):
    """Pixel by pixel: each cell's integral of exp(-2 pi i n.u) by 24-point Gauss-Legendre per axis."""
    rows, columns = weights.shape
    nodes, gauss = roots_legendre(24)
    n1, n2 = torus_modes((bandwidths[0] + 1, bandwidths[1] + 1))

    def cell_integrals(frequencies, cells):
        left = np.arange(cells)[:, None] / cells
        x = left + (nodes[None, :] + 1) / (2 * cells)
        return np.exp(-2j * np.pi * frequencies[:, None, None] * x[None]) @ gauss / (2 * cells)

    along_x = cell_integrals(n1[:, 0], columns)  # (N1+1, columns)
    along_y = cell_integrals(n2[0, :], rows)  # (N2+1, rows)
    return np.einsum("rc,ac,br->ab", weights, along_x, along_y)


@pytest.mark.parametrize("shape,bandwidth", [((5, 7), 6), ((6, 4), 20), ((3, 3), 30), ((41, 60), 8), ((75, 31), 6)])
def test_image_coefficients_are_exact_integrals(rng, shape, bandwidth):
    """Small images by their whole FFT; the last two, with 4 pixels per mode or more, by a real FFT of the rows and
    an FFT of the modes' columns (``image_dft``)."""
    weights = rng.random(shape)
    bandwidths = axis_bandwidths(bandwidth, shape)
    exact = brute_force_coefficients(weights, bandwidths)
    np.testing.assert_allclose(image_coefficients(weights, bandwidths), exact, atol=1e-14)


def test_pixel_density_shares_one_fft_and_one_peak_among_a_runs_problems(rng, monkeypatch):
    """A problem's coarse levels and its correction's coarse problems are built on the same ``PixelDensity``:
    the same exact coefficients at every bandwidth from one FFT, and one peak ratio."""
    weights = rng.random((30, 44)) ** 2
    density = PixelDensity(weights)
    for bandwidth in (8, 20, 44):
        bandwidths = axis_bandwidths(bandwidth, weights.shape)
        exact = brute_force_coefficients(weights, bandwidths)
        np.testing.assert_allclose(density.coefficients(bandwidths), exact, atol=1e-14)
    assert density.peak_ratio == peak_ratio(weights)
    # The largest bandwidths asked for are kept, and the smaller ones read from them, in the same bits.
    large = PixelDensity(rng.random((200, 300)))
    first = large.coefficients(axis_bandwidths(40, (200, 300)))
    again = large.coefficients(axis_bandwidths(12, (200, 300)))
    assert np.array_equal(again, image_coefficients(large.weights, axis_bandwidths(12, (200, 300))))
    assert np.array_equal(large.coefficients(axis_bandwidths(40, (200, 300))), first)
    calls = {"fft2": 0, "peak": 0}
    fft2, peak = np.fft.fft2, torus_spectrum.peak_ratio

    def counted(name, function):
        def call(*args, **kwargs):
            calls[name] += 1
            return function(*args, **kwargs)

        return call

    monkeypatch.setattr(np.fft, "fft2", counted("fft2", fft2))
    monkeypatch.setattr(torus_spectrum, "peak_ratio", counted("peak", peak))
    problem = torus_problem(weights, 400, threads=1)
    for other in (problem.level(100), problem.coarse(8), problem.coarse(4)):
        assert other.bandwidth < problem.bandwidth
    assert calls == {"fft2": 1, "peak": 1}


def test_axis_bandwidths_keep_resolution_isotropic():
    assert axis_bandwidths(100, (50, 100)) == (100, 50)
    assert axis_bandwidths(100, (100, 100)) == (100, 100)
    assert axis_bandwidths(10, (3, 100)) == (10, 2)


@pytest.mark.parametrize("k", [8, 13])
def test_lattice_has_zero_error_below_its_size(k):
    """A k×k lattice integrates exp(2 pi i n.u) exactly unless k divides both n_j: zero error while N/2 < k."""
    grid = (np.arange(k) + 0.5) / k
    lattice = np.stack(np.meshgrid(grid, grid, indexing="ij"), axis=-1).reshape(-1, 2)
    flat = np.ones((4, 4))
    below = torus_problem(flat, k * k, 2 * k - 2, threads=1, epsilon=1e-13, near_field=False).objective
    below.set_points(lattice)
    above = torus_problem(flat, k * k, 2 * k, threads=1, epsilon=1e-13, near_field=False).objective
    above.set_points(lattice)
    assert below.energy() < 1e-25
    assert above.energy() > 1e-6


def test_samples_follow_the_image():
    weights = np.zeros((4, 8))
    weights[1, 6] = 3.0
    weights[3, 0] = 1.0
    points = sample_image(weights, np.random.default_rng(0), 4000)
    in_first = (points[:, 0] >= 6 / 8) & (points[:, 0] < 7 / 8) & (points[:, 1] >= 1 / 4) & (points[:, 1] < 2 / 4)
    in_second = (points[:, 0] < 1 / 8) & (points[:, 1] >= 3 / 4)
    assert np.all(in_first | in_second)
    assert in_first.mean() == pytest.approx(0.75, abs=0.03)


def test_halftone_decreases_energy_monotonically_and_is_reproducible(rng):
    weights = np.outer(np.linspace(0.1, 1, 24), np.linspace(1, 0.2, 32))
    first = halftone_torus(weights, 300, 40, iterations=60, tol=1e-12, threads=1, seed=3, init="density")
    second = halftone_torus(weights, 300, 40, iterations=60, tol=1e-12, threads=1, seed=3, init="density")
    assert first.iterations == 60
    np.testing.assert_array_equal(first.points, second.points)
    rises = np.diff(first.energies) / first.energies[:-1]
    assert rises.max() < 1e-12
    assert first.energies[-1] < 0.2 * first.energies[0]
    assert np.all((first.points >= 0) & (first.points < 1))


@pytest.mark.parametrize("backend", backend_params(BACKENDS[1:]))
def test_backends_reach_the_same_energy(backend):
    weights = np.outer(np.linspace(0.1, 1, 16), np.ones(16))
    energies = [
        halftone_torus(weights, 200, 30, iterations=15, tol=1e-12, threads=1, backend=name, epsilon=1e-11).energies
        for name in ("ducc0", backend)
    ]
    np.testing.assert_allclose(energies[0], energies[1], rtol=1e-6)


@pytest.mark.parametrize("beta,fields_per_iteration", [("hestenes-stiefel", 2), ("daniel", 3)])
def test_type1_fields_per_iteration(beta, fields_per_iteration):
    """Residual plus the Jacobian of the new direction (Hestenes-Stiefel), or of the gradient and the old direction
    (Daniel); two more at the start (residual and the gradient's Jacobian). Plain objective: no restarts here."""
    weights = np.outer(np.linspace(0.1, 1, 16), np.ones(16))
    problem = torus_problem(weights, 200, 30, threads=1, near_field=False)
    # Without the spread step, whose own iterations use the same transforms.
    result = run(problem, init="density", iterations=12, tol=1e-12, beta=beta, spread=False)
    counts = problem.discrepancy.fourier.counts
    assert result.iterations == 12
    assert counts["type1"] == 2 + fields_per_iteration * 12
    assert counts["type2"] == 1 + 12


def test_full_hessian_also_descends():
    weights = np.outer(np.linspace(0.1, 1, 16), np.ones(16))
    result = halftone_torus(weights, 200, 30, iterations=30, tol=1e-12, threads=1, hessian="full", init="density")
    assert result.energies[-1] < 0.2 * result.energies[0]


def test_stops_at_tolerance():
    weights = np.ones((8, 8))
    result = halftone_torus(weights, 100, 16, iterations=5000, tol=1e-2, threads=1)
    assert result.status == "converged"
    assert result.relative_gradient_norm <= 1e-2


def test_stratified_start_gives_every_quadrant_its_share(rng):
    """Quadrants (and their quadrants) of a power-of-two image are stretches of the Hilbert curve, so each gets its
    share of the dots to within 2; i.i.d. samples miss by about sqrt(count)."""
    weights = rng.random((64, 64)) ** 3
    count = 4000
    points = stratified_sample(weights, rng, count)
    iid = sample_image(weights, rng, count)
    worst = {"stratified": 0.0, "iid": 0.0}
    for blocks in (2, 4, 8):
        size = 64 // blocks
        mass = weights.reshape(blocks, size, blocks, size).sum(axis=(1, 3)) / weights.sum()
        for name, sample in (("stratified", points), ("iid", iid)):
            cells = np.floor(sample * blocks).astype(int)
            counts = np.zeros((blocks, blocks))
            np.add.at(counts, (cells[:, 1], cells[:, 0]), 1)
            worst[name] = max(worst[name], np.abs(counts - count * mass).max())
    assert worst["stratified"] <= 2
    assert worst["iid"] > 10


@pytest.mark.parametrize("shape", [(64, 64), (100, 37), (301, 517)])
def test_stratified_cells_through_blocks_are_the_cells_through_every_pixel(rng, shape):
    """A large image's stratified start finds its cells among blocks of pixels first: the Hilbert curve visits each
    aligned block in one stretch, so the cells are those of the curve through every pixel (zeros included)."""
    weights = rng.random(shape) ** 3
    weights[:10, :20] = 0.0
    rows, columns = shape
    count = 200
    fractions = (np.arange(count) + rng.random(count)) / count
    row, column = np.divmod(np.arange(weights.size), columns)
    order = int(np.ceil(np.log2(max(shape))))
    every_pixel = _cells_at(weights, np.argsort(hilbert_index(column, row, order), kind="stable"), fractions)
    for level in (1, 2, 3):
        assert np.array_equal(_cells_through_blocks(weights, order, level, fractions), every_pixel)
    # stratified_cells takes the blocks where an image has 16^2 pixels a point or more.
    few = weights.size // 300
    assert MIN_BLOCK_LEVEL == 2 and int(np.log2(weights.size / few) // 4) == 2
    rng_a, rng_b = np.random.default_rng(5), np.random.default_rng(5)
    fractions = (np.arange(few) + rng_b.random(few)) / few
    assert np.array_equal(stratified_cells(weights, rng_a, few), _cells_through_blocks(weights, order, 2, fractions))


def test_stratified_start_is_the_default_and_tol_refers_to_iid_samples():
    weights = np.outer(np.linspace(0.1, 1, 24), np.linspace(1, 0.2, 32))
    stratified = halftone_torus(weights, 300, 40, iterations=0, threads=1, seed=3)
    iid = halftone_torus(weights, 300, 40, iterations=0, threads=1, seed=3, init="density")
    assert stratified.energies[0] < 0.5 * iid.energies[0]
    # The reference gradient is that of i.i.d. samples, so the stratified start is already part of the way.
    assert stratified.relative_gradient_norm < 0.5
    assert iid.relative_gradient_norm == 1.0


def direct_weighted_error(weights, points, bandwidth):
    """``sum_n k_n |lam sum_i e^{-2 pi i n.p_i} - w_n|^2`` over ``|n_j| <= N_j / 2``, by direct O(M N^2) sums."""
    bandwidths = axis_bandwidths(bandwidth, weights.shape)
    n1, n2 = torus_modes((bandwidths[0] + 1, bandwidths[1] + 1))
    phases = np.exp(-2j * np.pi * (np.outer(points[:, 0], n1.ravel()) + np.outer(points[:, 1], n2.ravel())))
    residual = weights.mean() / len(points) * phases.sum(axis=0) - image_coefficients(weights, bandwidths).ravel()
    kernel = torus_kernel(bandwidths, torus_scale(weights.shape)).ravel()
    return float(np.sum(kernel * np.abs(residual) ** 2))


def test_low_frequency_correction_fixes_the_lowest_modes_and_reports_the_energy_of_its_points():
    weights = 1 - np.outer(np.linspace(0, 1, 48), np.linspace(1, 0.1, 72)) ** 0.5
    problem = torus_problem(weights, 2000, threads=1)
    # The correction alone (the spread step has its own tests).
    plain = run(problem, iterations=60, tol=1e-12, correct=False, spread=False)
    corrected = run(problem, iterations=60, tol=1e-12, spread=False)
    lowest = problem.bandwidth // max(COARSE_LEVELS)[0]
    assert [level.iterations for level in corrected.corrections] == [count for _, count in COARSE_LEVELS]
    np.testing.assert_array_equal(corrected.state.points, plain.points)
    assert direct_weighted_error(weights, corrected.points, lowest) < 0.01 * direct_weighted_error(
        weights, plain.points, lowest
    )
    problem.objective.set_points(corrected.points)
    assert corrected.energy == pytest.approx(problem.objective.energy(), rel=1e-12)
    assert corrected.energy < 1.02 * plain.energy
    moves = (corrected.points - plain.points + 0.5) % 1.0 - 0.5
    distances = np.hypot(*(moves * torus_scale(weights.shape)).T)
    assert np.percentile(distances, 90) < 0.1 * 2000**-0.5  # a smooth deformation, not a rearrangement


def test_settle_stops_at_the_first_window_that_gains_less_than_the_fraction():
    weights = np.outer(np.linspace(0.1, 1, 24), np.linspace(1, 0.2, 32))
    problem = torus_problem(weights, 300, 40, threads=1)
    result = run(problem, init="density", tol=1e-12, iterations=3000, settle=0.01, correct=False)
    energies = result.energies
    gains = (energies[:-SETTLE_WINDOW] - energies[SETTLE_WINDOW:]) / np.abs(energies[SETTLE_WINDOW:])
    assert result.status == "settled"
    assert result.iterations == SETTLE_WINDOW + np.flatnonzero(gains < 0.01)[0]
    assert result.iterations < 3000
    never = run(problem, init="density", tol=1e-12, iterations=result.iterations + 5, settle=0, correct=False)
    assert never.status == "max_iterations"
    np.testing.assert_array_equal(never.energies[: len(energies)], energies)
    assert problem.settle == DEFAULT_SETTLE and run(problem, iterations=0).status == "max_iterations"


def test_single_precision_derivatives_keep_the_energy_and_steer_alike(rng):
    """``derivative_epsilon`` changes only the derivatives' transforms: the energy (the residual, at ``epsilon``)
    is the double-precision one to 1e-12, the gradient and the Hessian form are within 1e-4 of it; the levels and
    the coarse problems keep the setting; it is never finer than ``epsilon`` and is checked."""
    weights = 0.2 + rng.random((32, 48))
    points = rng.random((3000, 2))
    exact = torus_problem(weights, 3000, threads=1)
    single = torus_problem(weights, 3000, threads=1, derivative_epsilon=DERIVATIVE_EPSILON)
    assert_derivatives_alike(exact, single, points, points)
    assert single.discrepancy.fourier.nufft.epsilon == DERIVATIVE_EPSILON
    assert single.discrepancy.fourier.epsilon == exact.discrepancy.fourier.epsilon == DEFAULT_EPSILON
    for other in (single.level(1000), single.coarse(16)):
        assert other.discrepancy.fourier.nufft.epsilon == DERIVATIVE_EPSILON
    assert derivative_accuracy(1e-3, 1e-4) == 1e-3
    with pytest.raises(StippleError, match="epsilon"):
        torus_problem(weights, 3000, derivative_epsilon=float("nan"))


class _PastTheMemoryCheck(Exception):
    pass


@pytest.mark.parametrize(
    "shape, count, threads, available, refused",
    [
        ((32, 48), 20_000_000, 2, 22.8, True),
        ((1024, 1024), 1_000_000, 2, 2.6, False),
        ((1024, 1024), 1_000_000, 16, 3.0, True),
    ],
)
def test_the_memory_check_counts_what_a_point_costs(monkeypatch, shape, count, threads, available, refused):
    """20 million points on a 48 x 32 image were estimated at 15.4 GiB (320 bytes a point), passed on a machine
    with 22.8 GiB available, and were killed by the kernel at 23.5 GB; the default million-dot run, which peaks at
    2.50 GiB with 2 threads, still passes with 2.6 GiB available. With 16 threads it peaked at 3.45 GiB (a lent
    16-core machine), which 3 GiB must not let through."""
    import stipple.allocator
    import stipple.torus

    def past(*args):
        raise _PastTheMemoryCheck

    monkeypatch.setattr(stipple.allocator, "available_memory", lambda: available * 2**30)
    monkeypatch.setattr(stipple.torus, "make_nufft", past)
    with pytest.raises(StippleError if refused else _PastTheMemoryCheck):
        torus_problem(np.full(shape, 0.5), count, threads=threads)


@pytest.mark.parametrize("scale", [1e-80, 1e-30, 1e30, 1e200])
def test_weights_at_any_scale_give_the_same_dots(scale):
    """The dots are the same at any scale of the weights; at 1e-80 a run stopped as "converged" at its start and
    at 1e200 with a NaN energy (a hostile review of the API)."""
    from stipple import halftone_torus

    weights = np.random.default_rng(1).random((16, 16))
    plain = halftone_torus(weights, 50, iterations=3, threads=1)
    scaled = halftone_torus(weights * scale, 50, iterations=3, threads=1)
    assert scaled.status == plain.status == "max_iterations" and np.isfinite(scaled.energy)
    np.testing.assert_allclose(scaled.points, plain.points, atol=1e-12)


@pytest.mark.parametrize(
    "weights, message",
    [
        (np.ones((8, 8)) + 0j, "weights must be real numbers, not complex128"),
        (np.ma.masked_array(np.ones((8, 8)), mask=np.eye(8)), "a masked array"),
    ],
)
def test_complex_and_masked_weights_are_refused(weights, message):
    """numpy dropped the imaginary part (with a ComplexWarning) and the mask without a word."""
    with pytest.raises(StippleError, match=message):
        torus_problem(weights, 20)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"seed": -1}, "seed must be a non-negative integer"),
        ({"seed": 1.5}, "seed must be a non-negative integer"),
        ({"seed": None}, "seed must be a non-negative integer"),
        ({"restart_every": "a"}, "restart_every must be an integer in"),
        ({"restart_every": 0}, "restart_every must be an integer in"),
        ({"checkpoint_seconds": float("nan")}, "checkpoint_seconds must be a positive number"),
        ({"checkpoint_iterations": 1.5}, "checkpoint_iterations must be an integer in"),
    ],
)
def test_run_settings_are_checked_where_they_enter(options, message):
    """A seed of -1 or 1.5 failed in numpy's words, None gave other points at every call, a restart_every of "a"
    failed after the start was made, 0 acted as never (a hostile review of the API)."""
    problem = torus_problem(np.ones((8, 8)), 20, 8)
    with pytest.raises(StippleError, match=message):
        run(problem, iterations=2, **options)


def test_a_stop_asked_in_the_spread_step_stops_the_run():
    """A callback that asks to stop after the main run's iterations: the result said "max_iterations" and the
    correction ran on, calling it again (a hostile review of the API)."""
    weights = np.random.default_rng(2).random((32, 32)) ** 3
    problem = torus_problem(weights, 400)
    calls = []

    def stop_after_the_main_run(state):
        calls.append(state.iteration)
        return len(calls) > 9  # the main run shows its states 0 to 8

    result = run(problem, iterations=8, levels=False, callback=stop_after_the_main_run)
    assert "close dots spread" in result.message and result.status == "stopped"
    assert len(calls) == 10  # the main run's nine states, then the spread step's first: nothing after it


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda p: run(p, iterations=1, tol=True), "tol must be a positive number"),
        (lambda p: run(p, iterations=1, time_limit=1 + 0j), "time_limit must be a positive number"),
        (lambda p: run(p, iterations=1, settle=np.float32(0.001)), None),
        (lambda p: run(p, iterations=1, callback=5), "callback must be a function"),
        (lambda p: torus_problem(np.ones((8, 8)), 20, 8, derivative_epsilon=0.5), "derivative_epsilon must be"),
        (lambda p: torus_problem(np.ones((8, 8)), 20, 8, hessian="bogus"), "hessian must be"),
    ],
)
def test_odd_types_of_settings_are_checked_alike(make, message):
    """True and complex numbers passed as tol and time_limit, np.float32 was refused for settle, callback=5 failed
    at its first call, a bad derivative_epsilon was named epsilon, a bad hessian was a plain ValueError (a
    hostile review of the API)."""
    problem = torus_problem(np.ones((8, 8)), 20, 8)
    if message is None:
        make(problem)
        return
    with pytest.raises(StippleError, match=message):
        make(problem)


@pytest.mark.parametrize("checkpoint", [5, b"x.npz", "folder"])
def test_a_checkpoint_that_is_not_a_file_path_is_refused(tmp_path, monkeypatch, checkpoint):
    """5 and bytes failed in os's and tempfile's words; a folder was called an existing checkpoint."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder").mkdir()
    with pytest.raises(StippleError, match="checkpoint must be the path of a file"):
        run(torus_problem(np.ones((8, 8)), 20, 8), iterations=1, checkpoint=checkpoint)


@pytest.mark.parametrize(
    "init, message",
    [
        (np.zeros((30, 2)), "initial points must be M = 20 points of 2 coordinates, not 30 of 2"),
        (np.zeros(40), r"not an array of shape \(40,\)"),
        (np.zeros((20, 2)) + 0j, "initial points must be real numbers, not complex128"),
    ],
)
def test_a_start_of_the_wrong_count_names_m(init, message):
    """A --init CSV of 30150 points for -M 300 said 'must be real numbers of shape (300, 2)', which named neither
    the count nor M (a hostile review)."""
    with pytest.raises(StippleError, match=message):
        run(torus_problem(np.ones((8, 8)), 20, 8), init=init, iterations=1)


def test_kernels_of_small_grids_are_kept_read_only_and_equal_to_fresh_ones():
    # A video builds every frame's problem on the same grid; the kernels are computed once.
    shape, bandwidth = (128, 208), 214
    smooth, cross, near = torus_kernels(bandwidth, shape, True)
    assert torus_kernels(bandwidth, shape, True)[0] is smooth
    scale, bandwidths = torus_scale(shape), axis_bandwidths(bandwidth, shape)
    fresh_cross = radial_on_modes(torus_near_kernel(bandwidth, scale).plane_coefficients, bandwidths, scale)
    np.testing.assert_array_equal(cross, fresh_cross)
    np.testing.assert_array_equal(smooth, torus_kernel(bandwidths, scale) - fresh_cross)
    assert near.radius == torus_near_kernel(bandwidth, scale).radius
    plain, none, no_near = torus_kernels(bandwidth, shape, False)
    np.testing.assert_array_equal(plain, torus_kernel(bandwidths, scale))
    assert none is None and no_near is None
    for array in (smooth, cross, plain):
        with pytest.raises(ValueError):
            array[0, 0] = 1.0
    large = 2 * int(np.sqrt(CACHED_MODES) / 2) + 2  # a grid over CACHED_MODES modes is computed afresh every time
    assert torus_kernels(large, (64, 64), False)[0] is not torus_kernels(large, (64, 64), False)[0]
