"""``--order progressive``: nested levels, each its own term; passes drawn one after another."""

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import gradient_taylor_slope
from PIL import Image

from stipple.cli import main
from stipple.halftone import run
from stipple.measures.evaluate import discrepancy_energy
from stipple.progressive import (
    BETWEEN_SHARE,
    interleave,
    level_factors,
    pass_counts,
    pass_offsets,
    progressive_inks,
    progressive_order,
    progressive_problem,
    promised_levels,
)
from stipple.torus import default_bandwidth, torus_problem


@pytest.mark.parametrize("levels", [1, 2, 3, 4, 5, 8])
def test_passes_are_a_bit_reversed_deal(levels):
    offsets = pass_offsets(levels)
    assert sorted(offsets) == list(range(levels)) and offsets[0] == 0
    dealt = interleave(np.arange(37), levels)
    assert sorted(dealt) == list(range(37))
    counts = pass_counts(37, levels)
    assert sum(counts) == 37 and max(counts) - min(counts) <= 1
    ends = np.cumsum(counts)
    for offset, start, end in zip(offsets, ends - counts, ends, strict=True):
        assert list(dealt[start:end]) == list(range(offset, 37, levels))


def test_first_half_of_four_passes_is_every_other_dot():
    dealt = interleave(np.arange(40), 4)
    assert sorted(dealt[:20]) == list(range(0, 40, 2))


def density():
    y, x = np.mgrid[0:16, 0:20] / 16
    return 0.2 + 0.8 * np.exp(-((x - 0.6) ** 2 + (y - 0.4) ** 2) * 4)


def test_objective_is_the_weighted_sum_of_the_levels(rng):
    weights = density()
    problem = progressive_problem(weights, 48, threads=1)
    points = problem.manifold.random(rng, 48)
    problem.objective.set_points(points)
    ends = [12, 24, 36, 48]
    expected = 0.0
    for end, factor in zip(ends, [0.25, 1.0, 0.75 * BETWEEN_SHARE, 1.0], strict=True):
        level = torus_problem(weights, end, default_bandwidth(end, weights), threads=1)
        level.objective.set_points(points[:end])
        expected += factor * level.objective.energy()
    assert problem.objective.energy() == pytest.approx(expected, rel=1e-12)
    assert problem.settings["level_points"] == ends


@pytest.mark.parametrize(
    ("levels", "promised"), [(1, [1]), (2, [1, 2]), (3, [3]), (4, [1, 2, 4]), (6, [3, 6]), (8, [1, 2, 4, 8])]
)
def test_promised_levels_are_the_doublings(levels, promised):
    assert promised_levels(levels) == promised


def test_level_factors_count_each_doubling_neighbour():
    # Four passes of 12: the quarter doubles into the half, the half into the whole (twice its share), 75 % between.
    assert level_factors([12, 24, 36, 48]) == pytest.approx([0.25, 2 * 0.5, BETWEEN_SHARE * 0.75, 1.0], rel=1e-15)
    # Eight passes: 1/4 and 1/2 have two promised neighbours each, 1/8 and the whole set one.
    ends = np.arange(1, 9) * 10
    expected = [1 / 8, 2 / 4, BETWEEN_SHARE * 3 / 8, 2 / 2] + [BETWEEN_SHARE * k / 8 for k in (5, 6, 7)] + [1.0]
    assert level_factors(ends) == pytest.approx(expected, rel=1e-15)
    # One level is the plain problem's objective; shares are those of the actual ends (unequal passes).
    assert level_factors([37]) == [1.0]
    assert level_factors([10, 21]) == pytest.approx([10 / 21, 1.0], rel=1e-15)


def test_gradient_taylor_slope(rng):
    problem = progressive_problem(density(), 40, threads=1)
    points = problem.manifold.random(rng, 40)
    slope = gradient_taylor_slope(problem.objective, points, rng.standard_normal(points.shape), [1e-3, 5e-4])
    assert slope == pytest.approx(2, abs=0.1)


def test_every_level_is_a_good_stipple(rng):
    weights = density()
    count = 400
    nested = run(progressive_problem(weights, count, threads=1), seed=1, iterations=300).points
    plain = run(torus_problem(weights, count, threads=1), seed=1, iterations=300).points
    shuffled = plain[rng.permutation(count)]
    for end in (100, 200, 400):
        level = torus_problem(weights, end, threads=1)
        alone = run(level, seed=2, iterations=300).points
        ours = discrepancy_energy(level, nested[:end])
        assert ours <= 1.6 * discrepancy_energy(level, alone)
        if end < count:
            assert ours < 0.5 * discrepancy_energy(level, shuffled[:end])


def test_promised_levels_are_balanced():
    # The half, between two levels it cannot both be nested in as a near-hexagonal set, is as good as the quarter
    # and the whole relative to independent stipples; weighted by the shares of the dots alone it lagged (1.18).
    weights = density()
    count = 400
    ratios = {}
    for name, factors in [("balanced", None), ("shares", [0.25, 0.5, 0.75, 1.0])]:
        problem = progressive_problem(weights, count, threads=1)
        problem.objective.weights = problem.objective.weights if factors is None else factors
        nested = run(problem, seed=1, iterations=300).points
        ratios[name] = []
        for end in (100, 200, 300, 400):
            level = torus_problem(weights, end, threads=1)
            alone = run(level, seed=2, iterations=300).points
            ratios[name].append(discrepancy_energy(level, nested[:end]) / discrepancy_energy(level, alone))
    quarter, half, between, whole = ratios["balanced"]
    assert max(quarter, half, whole) < 1.12 and between < 1.8
    assert ratios["shares"][1] > 1.12


def test_passes_are_drawn_one_after_another(rng):
    centres = rng.random((90, 2)) * 100
    counts = [23, 22, 23, 22]
    order, before, after = progressive_order(centres, counts)
    assert sorted(order) == list(range(90))
    ends = np.cumsum(counts)
    for start, end in zip(ends - counts, ends, strict=True):
        assert sorted(order[start:end]) == list(range(start, end))
    assert after < before


def gray(tmp_path):
    path = tmp_path / "g.png"
    Image.fromarray((255 * (1 - density())).astype(np.uint8)).save(path)
    return path


def test_progressive_on_the_command_line(tmp_path):
    csv = tmp_path / "dots.csv"
    arguments = ["torus", str(gray(tmp_path)), "-M", "200", "--order", "progressive", "--iterations", "30"]
    result = CliRunner().invoke(main, [*arguments, "-o", str(csv)])
    assert result.exit_code == 0, result.output
    assert "in passes of 50, 50, 50, 50 dots" in result.output
    assert len(csv.read_text().splitlines()) == 201


@pytest.mark.parametrize("order", [["--order", "progressive"], []])
def test_resuming_with_or_without_progressive_names_the_option(tmp_path, order):
    """The message blamed -N, the bandwidth the option changes (a held-out review)."""
    checkpoint = tmp_path / "run.npz"
    arguments = ["torus", str(gray(tmp_path)), "-M", "200", "--iterations", "10", "-q", "--checkpoint", str(checkpoint)]
    assert CliRunner().invoke(main, [*arguments, *order, "-o", str(tmp_path / "a.csv")]).exit_code == 0
    other = [] if order else ["--order", "progressive"]
    result = CliRunner().invoke(main, [*arguments, *other, "--resume", "-o", str(tmp_path / "b.csv")])
    assert result.exit_code == 1 and "different run: --order progressive differs" in result.output, result.output


def test_bare_order_is_one_path(tmp_path):
    result = CliRunner().invoke(
        main, ["torus", str(gray(tmp_path)), "-M", "100", "--iterations", "5", "--order", "-o", str(tmp_path / "d.csv")]
    )
    assert result.exit_code == 0, result.output
    assert "pen-up travel" in result.output and "passes" not in result.output


@pytest.mark.parametrize("command", [["sphere", "builtin:gaussians"], ["colour", "IMAGE"], ["batch", "IMAGE"]])
def test_progressive_elsewhere_is_refused(tmp_path, command):
    command = [str(gray(tmp_path)) if part == "IMAGE" else part for part in command]
    extra = ["-d", str(tmp_path / "out")] if command[0] == "batch" else ["-o", str(tmp_path / "o.csv")]
    result = CliRunner().invoke(main, [*command, "-M", "50", "--iterations", "2", "--order", "progressive", *extra])
    assert result.exit_code != 0 and "progressive" in result.output and "Traceback" not in result.output


def test_vpype_plugin_progressive_keeps_one_layer_per_pen(tmp_path):
    vpype = pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import vpype_cli

    from stipple.render.pen import path_length

    image = gray(tmp_path)
    document = vpype_cli.execute(
        f"stipple -M 200 --iterations 40 --dot-style point --width 100mm --order progressive {image}"
    )
    (layer,) = document.layers.values()
    assert layer.property(vpype.METADATA_FIELD_NAME) == "black" and len(layer) == 200
    centres = np.array([path[0] for path in layer])
    # Pass by pass: each quarter alone is spread over the page (its dots' bounding box covers most of it) ...
    for start in range(0, 200, 50):
        part = centres[start : start + 50]
        assert np.ptp(part.real) > 0.7 * np.ptp(centres.real) and np.ptp(part.imag) > 0.7 * np.ptp(centres.imag)
    # ... and drawn along a short path: shorter than the passes' dots in a random order.
    rng = np.random.default_rng(0)
    shuffled = np.concatenate([rng.permutation(centres[start : start + 50]) for start in range(0, 200, 50)])
    pairs = np.stack([centres.real, centres.imag], axis=1)
    random_pairs = np.stack([shuffled.real, shuffled.imag], axis=1)
    assert path_length(pairs) < 0.5 * path_length(random_pairs)
    path = vpype_cli.execute(f"stipple -M 200 --iterations 40 --dot-style point --width 100mm --order path {image}")
    assert len(next(iter(path.layers.values()))) == 200


def two_inks():
    """A cyan blob over a magenta ramp (``cmy``: two inks)."""
    y, x = np.mgrid[0:24, 0:32] / 24
    rgb = np.ones((24, 32, 3))
    rgb[..., 0] = 1 - 0.7 * np.exp(-((x - 0.5) ** 2 + (y - 0.4) ** 2) * 6)
    rgb[..., 1] = 1 - 0.6 * x / x.max()
    return rgb


def test_inks_objective_is_every_inks_levels_and_the_union(rng):
    from stipple.colour import colour_problem

    layers, joint = colour_problem(two_inks(), 90, separation="cmy", union_weight=0.7, threads=1)
    problem, counts = progressive_inks(layers, joint, threads=1)
    points = problem.manifold.random(rng, 90)
    problem.objective.set_points(points)
    expected, start = 0.0, 0
    for layer, passes in zip(layers, counts, strict=True):
        ends = np.cumsum(passes)
        for end, factor in zip(ends, level_factors(ends), strict=True):
            level = torus_problem(layer.density, int(end), default_bandwidth(int(end), layer.density), threads=1)
            level.objective.set_points(points[start : start + end])
            expected += factor * level.objective.energy()
        start += ends[-1]
    union = torus_problem(sum(layer.density for layer in layers), 90, joint.bandwidth, threads=1)
    union.objective.set_points(points)
    expected += 0.7 * union.objective.energy()
    assert start == 90 and [len(passes) for passes in counts] == [4, 4]
    assert problem.objective.energy() == pytest.approx(expected, rel=1e-12)


def test_every_inks_levels_are_good_stipples_and_the_inks_avoid_each_other():
    from stipple.progressive import progressive_colour

    rgb, count = two_inks(), 800
    unions = {}
    for union_weight in (1.0, 0.0):
        layers, result, counts = progressive_colour(
            rgb, count, separation="cmy", union_weight=union_weight, threads=1, seed=1, iterations=300
        )
        union = torus_problem(sum(layer.density for layer in layers), count, threads=1)
        alone = run(union, seed=2, iterations=300).points
        unions[union_weight] = discrepancy_energy(union, result.points) / discrepancy_energy(union, alone)
    start = 0
    for layer, passes in zip(layers, counts, strict=True):
        ends = np.cumsum(passes)
        for k, end in enumerate(ends, start=1):
            level = torus_problem(layer.density, int(end), threads=1)
            ratio = discrepancy_energy(level, result.points[start : start + end])
            ratio /= discrepancy_energy(level, run(level, seed=2, iterations=300).points)
            assert ratio < (1.25 if k in promised_levels(len(passes)) else 1.9)
        start += ends[-1]
    # The union's term keeps the inks' dots apart: without it all the dots together are far less even.
    assert unions[1.0] < 1.3 and unions[0.0] > 1.5


def test_vpype_plugin_progressive_keeps_the_passes_per_pen(tmp_path):
    vpype = pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import vpype_cli

    rgb = tmp_path / "rgb.png"
    Image.fromarray((255 * two_inks()).astype(np.uint8)).save(rgb)
    document = vpype_cli.execute(
        f"stipple -M 400 --iterations 40 --dot-style point --width 100mm --separation cmy --order progressive {rgb}"
    )
    layers = {layer.property(vpype.METADATA_FIELD_NAME): layer for layer in document.layers.values()}
    assert sorted(layers) == ["cyan", "magenta"] and sum(len(layer) for layer in layers.values()) == 400
    for layer in layers.values():
        centres = np.array([path[0] for path in layer])
        quarter = len(centres) // 4
        # Each pen's first pass alone is spread over the page (its dots' bounding box covers most of that pen's).
        first = centres[:quarter]
        assert np.ptp(first.real) > 0.6 * np.ptp(centres.real) and np.ptp(first.imag) > 0.6 * np.ptp(centres.imag)


def test_low_frequency_correction_runs_on_the_full_set():
    problem = progressive_problem(density(), 48, threads=1)
    coarse = problem.coarse(8)
    assert coarse.n_points == 48 and coarse.bandwidth == 8 and problem.settle > 0


def test_too_few_dots_for_the_passes_is_named_so(tmp_path):
    """The message said 'levels must be an integer in [1, M = 3]', which reads as the unrelated --levels."""
    image = tmp_path / "g.png"
    Image.fromarray(np.tile(np.linspace(0, 255, 16).astype(np.uint8), (12, 1))).save(image)
    result = CliRunner().invoke(
        main, ["torus", str(image), "-M", "3", "-q", "--order", "progressive", "-o", str(tmp_path / "o.svg")]
    )
    assert result.exit_code == 1
    assert "--order progressive draws 4 passes, so it needs at least 4 dots, not -M 3" in result.output
