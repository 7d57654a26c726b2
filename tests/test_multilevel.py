"""The coarse-to-fine start (``stipple.multilevel``) and the density-scaled metric (``ScaledTorus``), each by its
own property: direct sums against the fast cell masses, exact lattices, the metric's Riesz identity, and energies
against plain runs; the same transfer on the sphere."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from stipple import multilevel
from stipple.design import fibonacci_lattice
from stipple.halftone import hexagonal_spacing, run
from stipple.manifolds import ScaledTorus, Sphere, Torus
from stipple.multilevel import (
    BLOCK_SAMPLES,
    SAMPLES_PER_CELL,
    cell_masses,
    coarse_to_fine,
    level_counts,
    shares,
    sphere_cell_masses,
    split_points,
    split_sphere_points,
)
from stipple.sphere import sphere_problem
from stipple.sphere_density import CellMap
from stipple.torus import (
    STIFFNESS_FLOOR,
    STIFFNESS_POWER,
    cell_means,
    periodic_blur,
    stiffness_field,
    torus_problem,
)
from stipple.torus_spectrum import torus_scale
from stipple.transforms import spherical_angles


def brute_force_masses(weights, points, scale, factor):
    """The mass of every sub-pixel given to the nearest point by direct periodic distances (O(samples x M))."""
    rows, columns = weights.shape
    x = (np.arange(columns * factor) + 0.5) / (columns * factor)
    y = (np.arange(rows * factor) + 0.5) / (rows * factor)
    xx, yy = np.meshgrid(x, y)
    values = np.repeat(np.repeat(weights, factor, axis=0), factor, axis=1).ravel()
    delta = np.stack([xx.ravel(), yy.ravel()], axis=1)[:, None, :] - points[None, :, :]
    delta -= np.rint(delta)
    distance = np.sum((delta * scale) ** 2, axis=2)
    owner = np.argmin(distance, axis=1)
    masses = np.bincount(owner, weights=values, minlength=len(points))
    return masses / masses.sum()


@pytest.mark.parametrize("shape", [(12, 12), (9, 17)])
def test_cell_masses_are_the_nearest_point_sums(rng, shape):
    weights = rng.random(shape)
    weights[0, :3] = 0.0
    points = rng.random((40, 2))
    scale = torus_scale(shape)
    factor = int(np.ceil(np.sqrt(16 * len(points) / weights.size)))
    fast = cell_masses(weights, points, scale)
    assert np.allclose(fast, brute_force_masses(weights, points, scale, factor), atol=1e-12)
    assert fast.sum() == pytest.approx(1.0)


@pytest.mark.parametrize("shape", [(300, 400), (301, 397)])
def test_cell_masses_of_a_large_image_are_its_pixel_blocks_nearest_point_sums(rng, shape):
    """With far more pixels than samples per dot the pixels are gathered into blocks (smaller along the far
    edges), each block's mass to the dot nearest its centre: by direct periodic distances."""
    weights = rng.random(shape)
    points = rng.random((100, 2))
    scale = torus_scale(shape)
    block = int(np.sqrt(weights.size / (BLOCK_SAMPLES * SAMPLES_PER_CELL * len(points))))
    assert block == 4
    starts = [np.arange(0, size, block) for size in shape]
    sums = np.add.reduceat(np.add.reduceat(weights, starts[0], axis=0), starts[1], axis=1)
    y, x = ((start + np.minimum(start + block, size)) / 2 / size for start, size in zip(starts, shape, strict=True))
    xx, yy = np.meshgrid(x, y)
    delta = np.stack([xx.ravel(), yy.ravel()], axis=1)[:, None, :] - points[None, :, :]
    delta -= np.rint(delta)
    owner = np.argmin(np.sum((delta * scale) ** 2, axis=2), axis=1)
    expected = np.bincount(owner, weights=sums.ravel(), minlength=len(points))
    fast = cell_masses(weights, points, scale)
    assert np.allclose(fast, expected / expected.sum(), atol=1e-12)
    # Near the pixels' own masses (every pixel cut in 29 x 29): blocks are a coarser sampling, not another measure.
    fine = cell_masses(weights, points, scale, samples_per_cell=10**6)
    assert np.mean(np.abs(fast - fine) / fine) < 0.03


def test_shares_keep_the_mass_of_every_cell_and_of_every_run_of_cells_along_the_curve(rng):
    masses = rng.random(300) ** 3
    masses /= masses.sum()
    points = rng.random((300, 2))
    for total in (300, 1200, 1237):
        counts = shares(masses, points, total)
        assert counts.sum() == total and np.all(counts >= 0)
        # Each cell: within one dot of its mass.
        assert np.all(np.abs(counts - total * masses) < 1.0)


def test_split_keeps_the_mass_in_every_cell(rng):
    """Every coarse dot gets children in proportion to the density's mass in its own cell (to within one)."""
    weights = rng.random((24, 24)) ** 2
    weights[:8, :8] = 0.0
    coarse = torus_problem(weights, 150, near_field=False).sample(rng, 150)
    scale = torus_scale(weights.shape)
    fine = split_points(weights, coarse, 600, scale)
    assert fine.shape == (600, 2) and np.all((fine >= 0) & (fine < 1))
    expected = 600 * brute_force_masses(weights, coarse, scale, int(np.ceil(np.sqrt(16 * 150 / weights.size))))
    counts = shares(cell_masses(weights, coarse, scale), coarse, 600)
    assert np.all(np.abs(counts - expected) < 1.0 + 1e-9)
    # The children of a dot sit around it, within its neighbourhood.
    owner = np.repeat(np.arange(len(coarse)), counts)
    delta = fine - coarse[owner]
    delta -= np.rint(delta)
    assert np.max(np.hypot(*(delta * scale).T)) < 0.5


@pytest.mark.parametrize("k", [4, 7])
def test_split_of_a_lattice_is_the_lattice_of_half_its_spacing(k):
    """For a constant density the transfer is exact: a k x k lattice becomes the 2k x 2k lattice, whose
    bandlimited error vanishes below its size (an oracle independent of the split)."""
    weights = np.ones((8 * k, 8 * k))
    grid = (np.arange(k) + 0.5) / k
    coarse = np.stack([c.ravel() for c in np.meshgrid(grid, grid)], axis=1)
    fine = split_points(weights, coarse, 4 * k * k, (1.0, 1.0))
    half = (np.arange(2 * k) + 0.5) / (2 * k)
    expected = np.stack([c.ravel() for c in np.meshgrid(half, half)], axis=1)
    key = lambda p: np.lexsort((np.round(p[:, 0], 9), np.round(p[:, 1], 9)))  # noqa: E731
    assert np.allclose(fine[key(fine)], expected[key(expected)], atol=1e-12)
    problem = torus_problem(weights, 4 * k * k, 2 * k - 2, near_field=False, epsilon=1e-12)
    problem.objective.set_points(fine)
    assert problem.objective.energy() < 1e-20


def nearest_distances(points, scale):
    """Each point's distance to its nearest other point (physical, periodic)."""
    positions = np.mod(points, 1.0) * scale
    return cKDTree(positions, boxsize=np.asarray(scale) * (1 + 1e-12)).query(positions, k=2)[0][:, 1]


def test_split_under_a_narrow_peak_never_puts_children_on_top_of_each_other():
    """A coarse level that does not resolve a narrow peak gives its dots there 40-70 children each (more than the
    36 lattice points the split once took them from, which then repeated the last one; and unshrunk patches of
    neighbouring dots met on the same points). Every child must be distinct, the closest pair a fair fraction of
    the spacing the densest cell's children need."""
    y, x = np.mgrid[0:128, 0:128] + 0.5
    weights = np.exp(-((x - 64) ** 2 + (y - 64) ** 2) / (2 * 4.0**2))
    grid = (np.arange(24) + 0.5) / 24
    coarse = np.stack([c.ravel() for c in np.meshgrid(grid, grid)], axis=1)
    fine = split_points(weights, coarse, 6000, (1.0, 1.0))
    counts = shares(cell_masses(weights, coarse, (1.0, 1.0)), coarse, 6000)
    assert counts.max() > 36
    assert len(np.unique(fine, axis=0)) == len(fine)
    densest = hexagonal_spacing(counts.max() * 24 * 24, 1.0)  # children per unit area in the densest cell
    assert nearest_distances(fine, (1.0, 1.0)).min() > 0.3 * densest


def test_split_of_dots_along_a_line_gives_distinct_children():
    """Dots on a line have no second neighbour direction: the lattice takes the first turned by a right angle."""
    coarse = np.stack([(np.arange(50) + 0.5) / 50, np.full(50, 0.5)], axis=1)
    owner, offsets = multilevel.lattice_offsets(*multilevel.lattice_vectors(coarse, (1.0, 1.0)), np.full(50, 6))
    fine = coarse[owner] + offsets
    assert len(np.unique(np.round(fine, 12), axis=0)) == len(fine)
    assert nearest_distances(fine, (1.0, 1.0)).min() > 0.25 / 50


def test_level_counts_quarter_the_dots_down_to_the_smallest():
    assert level_counts(100_000) == [6250, 25000]
    assert level_counts(7999) == []
    assert level_counts(8000) == [2000]
    counts = level_counts(10**6)
    assert counts[-1] == 250000 and all(abs(b - 4 * a) <= 2 for a, b in zip(counts[:-1], counts[1:], strict=False))


def test_scaled_metric_gradient_is_the_riesz_representative(rng):
    """``inner(p, riesz(p, c), v) = c . v`` for every v: the gradient in the scaled metric represents the same
    differential, so CG minimises the same energy."""
    field = 0.1 + rng.random((5, 7))
    manifold = ScaledTorus((1.0, 5 / 7), field)
    points, covector, vector = rng.random((30, 2)), rng.standard_normal((30, 2)), rng.standard_normal((30, 2))
    assert manifold.inner(points, manifold.riesz(points, covector), vector) == pytest.approx(
        float(np.sum(covector * vector)), rel=1e-12
    )
    rows = np.minimum((points[:, 1] * 5).astype(int), 4)
    columns = np.minimum((points[:, 0] * 7).astype(int), 6)
    assert np.array_equal(manifold.factor(points), field[rows, columns])
    with pytest.raises(ValueError):
        ScaledTorus((1.0, 1.0), np.zeros((2, 2)))


def test_stiffness_field_grows_with_the_density():
    weights = np.tile(np.linspace(0.0, 1.0, 32), (32, 1))
    field = stiffness_field(weights, 2000)
    assert np.all(field > 0) and np.all(np.diff(field[:, 3:-3], axis=1) > 0)
    assert np.allclose(stiffness_field(np.ones((10, 20)), 500), 1.0)


def inputs():
    y, x = np.mgrid[0:40, 0:40] / 40
    gradient = 0.05 + 0.95 * x
    disc = np.where((x - 0.5) ** 2 + (y - 0.5) ** 2 < 0.09, 1.0, 0.1)
    strip = np.tile(0.2 + 0.8 * np.sin(np.pi * np.linspace(0, 1, 60)) ** 2, (20, 1))
    return [gradient, disc, strip]


@pytest.mark.parametrize("index", range(3))
def test_coarse_to_fine_and_the_scaled_metric_never_end_above_a_plain_run(index):
    """Same number of full-size iterations, from the same seed: the new start and metric end at an energy no
    higher than the flat metric from the stratified start, on three inputs."""
    weights = inputs()[index]
    count, iterations = 2400, 30
    plain = torus_problem(weights, count, precondition=False)
    plain_result = run(plain, iterations=iterations, settle=0, correct=False, levels=False)
    new = torus_problem(weights, count)
    start = coarse_to_fine(new, np.random.default_rng(0), smallest=300)
    new_result = run(new, init=start, iterations=iterations, settle=0, correct=False)
    assert new_result.energy <= plain_result.energy
    assert isinstance(plain.manifold, Torus) and not isinstance(plain.manifold, ScaledTorus)


def test_coarse_to_fine_without_levels_is_the_stratified_start(rng):
    weights = inputs()[0]
    problem = torus_problem(weights, 500)
    start = coarse_to_fine(problem, np.random.default_rng(3))
    assert np.array_equal(start, problem.stratified(np.random.default_rng(3), 500))


def test_coarse_to_fine_start_is_reproducible_and_used_by_default(monkeypatch):
    weights = inputs()[1]
    monkeypatch.setattr(multilevel, "SMALLEST", 300)
    problem = torus_problem(weights, 1500)
    first = run(problem, iterations=3, correct=False)
    second = run(torus_problem(weights, 1500), iterations=3, correct=False)
    assert np.array_equal(first.points, second.points)
    plain = run(torus_problem(weights, 1500), iterations=3, correct=False, levels=False)
    assert not np.array_equal(first.points, plain.points)


# The sphere: the same transfer on a cell map (``split_sphere_points``).


def brute_force_sphere_masses(cells, points, factor):
    """Each sub-cell's mass (its exact area times the value) given to the nearest point by direct geodesic
    distances (O(samples x M)); sub-cells equal in colatitude and longitude."""
    rows, columns = cells.values.shape
    edges = np.linspace(0, np.pi, rows * factor + 1)
    theta = (edges[:-1] + edges[1:]) / 2
    phi = (np.arange(columns * factor) + 0.5) * 2 * np.pi / (columns * factor)
    areas = (np.cos(edges[:-1]) - np.cos(edges[1:]))[:, None] * np.full(
        columns * factor, 2 * np.pi / (columns * factor)
    )
    tt, pp = np.meshgrid(theta, phi, indexing="ij")
    centres = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], axis=-1).reshape(-1, 3)
    values = np.repeat(np.repeat(cells.values, factor, axis=0), factor, axis=1)
    owner = np.argmax(centres @ points.T, axis=1)
    masses = np.bincount(owner, weights=(values * areas).ravel(), minlength=len(points))
    return masses / masses.sum()


def test_sphere_cell_masses_are_the_nearest_point_sums(rng):
    values = rng.random((9, 18))
    values[0] = 0.0
    cells = CellMap(values)
    points = Sphere().random(rng, 40)
    factor = int(np.ceil(np.sqrt(16 * len(points) / values.size)))
    fast = sphere_cell_masses(cells, points)
    assert np.allclose(fast, brute_force_sphere_masses(cells, points, factor), atol=1e-12)
    assert fast.sum() == pytest.approx(1.0)


def test_sphere_cell_masses_of_a_large_map_are_its_blocks_nearest_point_sums(rng):
    """A map of far more cells than samples per dot is gathered into blocks (smaller along the last rows and
    columns), each block's exact mass to the dot nearest its centre in colatitude and longitude."""
    rows, columns = 130, 262
    values = rng.random((rows, columns))
    cells = CellMap(values, lon0=-30.0)
    points = Sphere().random(rng, 20)
    block = int(np.sqrt(values.size / (BLOCK_SAMPLES * SAMPLES_PER_CELL * len(points))))
    assert block == 5
    edges = np.cos(np.linspace(0, np.pi, rows + 1))
    areas = (edges[:-1] - edges[1:])[:, None] * np.full(columns, 2 * np.pi / columns)
    top, left = np.arange(0, rows, block), np.arange(0, columns, block)
    sums = np.add.reduceat(np.add.reduceat(values * areas, top, axis=0), left, axis=1)
    theta = (top + np.minimum(top + block, rows)) / 2 * np.pi / rows
    phi = np.radians(-30.0) + (left + np.minimum(left + block, columns)) / 2 * 2 * np.pi / columns
    tt, pp = np.meshgrid(theta, phi, indexing="ij")
    centres = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], axis=-1).reshape(-1, 3)
    owner = np.argmax(centres @ points.T, axis=1)
    expected = np.bincount(owner, weights=sums.ravel(), minlength=len(points))
    fast = sphere_cell_masses(cells, points)
    assert np.allclose(fast, expected / expected.sum(), atol=1e-12)
    fine = brute_force_sphere_masses(CellMap(values), points, 1)  # every cell: near, a coarser sampling only
    assert np.mean(np.abs(sphere_cell_masses(CellMap(values), points) - fine) / fine) < 0.05


def test_sphere_split_keeps_the_mass_in_every_cell_and_children_stay_near(rng):
    values = rng.random((18, 36)) ** 2
    values[:4] = 0.0
    cells = CellMap(values)
    coarse = cells.sample(rng, 200)
    fine = split_sphere_points(cells, coarse, 800)
    assert fine.shape == (800, 3) and np.allclose(np.linalg.norm(fine, axis=1), 1.0, atol=1e-14)
    theta, phi = spherical_angles(coarse)
    curve = np.stack([np.mod(phi / (2 * np.pi), 1.0), theta / np.pi], axis=1)
    counts = shares(sphere_cell_masses(cells, coarse), curve, 800)
    factor = int(np.ceil(np.sqrt(16 * 200 / values.size)))
    assert np.all(np.abs(counts - 800 * brute_force_sphere_masses(cells, coarse, factor)) < 1.0 + 1e-9)
    # The children of a dot are its own, consecutive, and sit around it within a few coarse spacings.
    owner = np.repeat(np.arange(len(coarse)), counts)
    assert np.max(np.linalg.norm(fine - coarse[owner], axis=1)) < 4 * hexagonal_spacing(200, 4 * np.pi) * 3


def test_sphere_split_under_a_narrow_peak_never_puts_children_on_top_of_each_other():
    """The torus's peak test on the sphere (a 4-degree bump; once 684 of 20000 dots of `stipple sphere` shared a
    position with another, which neither CG nor the spread step could separate)."""
    theta = np.linspace(0, np.pi, 91)[:-1] + np.pi / 180
    values = np.exp(-((theta - np.pi / 2) ** 2) / (2 * np.radians(4.0) ** 2))[:, None] * np.ones((1, 180))
    values *= np.exp(-(np.linspace(-np.pi, np.pi, 181)[:-1] ** 2) / (2 * np.radians(4.0) ** 2))[None, :]
    cells = CellMap(values)
    coarse = fibonacci_lattice(400)
    fine = split_sphere_points(cells, coarse, 4000)
    theta_c, phi_c = spherical_angles(coarse)
    curve = np.stack([np.mod(phi_c / (2 * np.pi), 1.0), theta_c / np.pi], axis=1)
    assert shares(sphere_cell_masses(cells, coarse), curve, 4000).max() > 36
    chord = cKDTree(fine).query(fine, k=2)[0][:, 1]
    assert chord.min() > 0


def test_sphere_split_of_a_spread_set_on_a_constant_map_gives_four_children_around_each_dot():
    """A constant density and an (almost) equal-area coarse set: every dot's cell holds a quarter of the children
    to within one, and four children sit symmetrically around their dot (their mean is the dot, up to the
    curvature's second-order term)."""
    cells = CellMap(np.ones((90, 180)))
    coarse = fibonacci_lattice(500)
    fine = split_sphere_points(cells, coarse, 2000)
    theta, phi = spherical_angles(coarse)
    curve = np.stack([np.mod(phi / (2 * np.pi), 1.0), theta / np.pi], axis=1)
    counts = shares(sphere_cell_masses(cells, coarse), curve, 2000)
    assert np.all(np.abs(counts - 4) <= 1)
    four = np.flatnonzero(counts == 4)
    starts = np.cumsum(counts) - counts
    centres = np.stack([fine[s : s + 4].mean(axis=0) for s in starts[four]])
    spacing = hexagonal_spacing(500, 4 * np.pi)
    assert np.max(np.linalg.norm(centres - coarse[four], axis=1)) < 0.1 * spacing
    # The fine set has half the coarse spacing (children of neighbouring dots may nearly meet: CG parts them).
    nearest = cKDTree(fine).query(fine, k=2)[0][:, 1]
    assert np.median(nearest) == pytest.approx(hexagonal_spacing(2000, 4 * np.pi), rel=0.2)


def sphere_maps():
    theta, phi = np.meshgrid(np.linspace(0, np.pi, 60), np.linspace(0, 2 * np.pi, 120), indexing="ij")
    band = 0.2 + 0.8 * np.sin(theta) ** 2
    bump = 0.05 + np.exp(-((theta - 1.0) ** 2 + (phi - 2.0) ** 2) / 0.2)
    halves = np.where(phi < np.pi, 1.0, 0.15)
    return [band, bump, halves]


@pytest.mark.parametrize("index", range(3))
def test_sphere_maps_start_coarse_to_fine_and_end_no_higher_than_the_stratified_start(index):
    problem = sphere_problem(sphere_maps()[index], 2400, threads=2)
    assert problem.level(600).n_points == 600 and problem.level(600).bandwidth < problem.bandwidth
    start = coarse_to_fine(problem, np.random.default_rng(0), smallest=150)
    stratified = problem.stratified(np.random.default_rng(0), 2400)
    energies = []
    for points in (start, stratified):
        problem.objective.set_points(points)
        energies.append(problem.objective.energy())
    assert energies[0] < 0.7 * energies[1]
    ends = [run(problem, init=points, iterations=20, settle=0, spread=False).energy for points in (start, stratified)]
    assert ends[0] <= ends[1]


def test_sphere_designs_have_no_levels():
    """A design's "stratified" start is its i.i.d. start, as before."""
    design = sphere_problem(None, 9000, threads=2)
    assert design.level is None and design.stratified is None and design.split is None


@pytest.mark.parametrize("sigma", [3.0, 40.0])
def test_the_metric_blur_is_the_periodic_gaussian_at_any_width(sigma):
    """Above DIRECT_BLUR_SIGMA the blur goes through the FFT (a direct filter of a 9000² image with 300 dots took
    minutes at 560 px): the periodic Gaussian still, its mean kept, a bump across an edge blurred across it."""
    from scipy.ndimage import gaussian_filter

    from stipple.torus import DIRECT_BLUR_SIGMA, periodic_blur

    values = np.zeros((160, 240))
    values[:5, :7] = 1.0  # a corner: its blur wraps around every edge
    values += np.random.default_rng(2).random(values.shape) * 0.1
    direct = gaussian_filter(values, sigma, mode="wrap", truncate=8.0)
    blurred = periodic_blur(values, sigma)
    assert (sigma > DIRECT_BLUR_SIGMA) == (sigma == 40.0)
    tolerance = 1e-9 if sigma > DIRECT_BLUR_SIGMA else 1e-3  # the direct filter truncates at 4 sigma
    assert np.abs(blurred - direct).max() < tolerance * np.abs(direct - direct.mean()).max()
    assert blurred.mean() == pytest.approx(values.mean(), rel=1e-12)


@pytest.mark.parametrize("sigma", [3.0, 30.0])
def test_the_sphere_metric_blur_at_any_width(sigma):
    """The sphere's metric blurs its map periodically in longitude and with the edge rows repeated in latitude;
    above DIRECT_BLUR_SIGMA through the FFT of the padded map (a 3000×6000 map with 300 dots took 18 s)."""
    from scipy.ndimage import gaussian_filter

    from stipple.sphere import map_blur

    values = np.random.default_rng(3).random((90, 180))
    values[:4] = 2.0  # a dark pole: the rows beyond it repeat it
    direct = gaussian_filter(values, sigma, mode=("nearest", "wrap"))
    assert np.abs(map_blur(values, sigma) - direct).max() < 1e-3 * np.ptp(direct)


def test_the_video_blur_of_a_stack_is_each_frames():
    from scipy.ndimage import gaussian_filter

    from stipple.video import _blur

    stack = np.random.default_rng(4).random((3, 40, 60))
    expected = gaussian_filter(stack, (0, 2.5, 2.5), mode="wrap")
    assert np.array_equal(_blur(stack, 2.5), expected) and np.array_equal(_blur(stack[0], 2.5), expected[0])


@pytest.mark.parametrize("shape, size", [((40, 60), 4.0), ((37, 53), 5.7), ((9, 31), 3.0), ((20, 20), 1.9)])
def test_cell_means_are_the_means_of_the_pixels_centred_in_uniform_cells(rng, shape, size):
    values = rng.random(shape)
    means = cell_means(values, size)
    if size < 2:
        assert means is values
        return
    cells = tuple(-(-length // int(size)) for length in shape)
    assert means.shape == cells
    # By definition: the pixel whose centre lies in cell (i, j) of the uniform grid belongs to it.
    row_cell, column_cell = (((np.arange(n) + 0.5) / n * c).astype(int) for n, c in zip(shape, cells, strict=True))
    for i in range(cells[0]):
        for j in range(cells[1]):
            inside = values[np.ix_(row_cell == i, column_cell == j)]
            assert inside.size > 0 and means[i, j] == pytest.approx(inside.mean(), rel=1e-12)


def test_stiffness_field_of_a_large_image_is_its_pixels_field_on_quarter_spacing_cells(rng):
    """Blurred at one dot spacing on cells of a quarter spacing (21 px here), the field is the pixels' own to a
    few per cent: a metric's factor, not a measure."""
    y, x = np.mgrid[0:900, 0:1300]
    weights = 0.05 + np.sin(x / 60.0) ** 2 * np.cos(y / 45.0) ** 2 + 3.0 * (rng.random((900, 1300)) < 0.01)
    field = stiffness_field(weights, 3000)
    spacing = hexagonal_spacing(3000, np.prod(torus_scale(weights.shape))) * 1300
    assert field.shape == (180, 260)
    blurred = periodic_blur(weights, spacing)
    pixels = np.maximum(blurred / blurred.mean(), STIFFNESS_FLOOR) ** STIFFNESS_POWER
    rows, columns = (((np.arange(n) + 0.5) / n * c).astype(int) for n, c in zip((900, 1300), field.shape, strict=True))
    error = np.abs(field[np.ix_(rows, columns)] - pixels) / pixels
    assert np.mean(error) < 0.04 and np.max(error) < 0.15
    # The constant density's field is 1 on any grid.
    assert np.allclose(stiffness_field(np.full((900, 1300), 0.3), 3000), 1.0)
