"""Tone-true radii (``stipple.tone``): the drawn union of discs has the image's darkness, darks included.

The oracle for what is drawn is a brute-force union of discs: many sample points per pixel, each tested
against the discs around it (``covered``), independent of the rasteriser under test.
"""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter
from scipy.spatial import cKDTree

import stipple
from stipple.colour import halftone_colour, separate
from stipple.errors import StippleError
from stipple.render.dots import periodic_tone_dots
from stipple.tone import (
    fit_inside,
    ink_ratio,
    multiply_colour,
    multiply_picture,
    multiply_separation,
    tone_radii,
    tone_radii_layers,
    union_coverage,
    union_coverage_image,
)
from stipple.tone.wrap import wrapped_copies


def covered(centres, radii, points):
    """Whether each point lies inside one of the discs (brute force over its nearest centres)."""
    count = min(len(centres), 24)
    distances, index = cKDTree(centres).query(points, k=count)
    distances, index = distances.reshape(len(points), -1), index.reshape(len(points), -1)
    # No disc beyond the nearest ``count`` centres can reach the point: the oracle sees every disc.
    assert count == len(centres) or np.all(distances[:, -1] >= radii.max())
    return np.any(distances < radii[index], axis=1)


def samples(size, shape, per_pixel, offset):
    """``per_pixel``² sample points a pixel, on a grid offset by ``offset`` fine pixels."""
    rows, columns = shape
    width, height = size
    fine_x = (np.arange(columns * per_pixel) + offset) * width / (columns * per_pixel)
    fine_y = (np.arange(rows * per_pixel) + offset) * height / (rows * per_pixel)
    return np.stack(np.meshgrid(fine_x, fine_y), axis=-1).reshape(-1, 2)


def oracle_image(centres, radii, size, shape, per_pixel=9, offset=0.37):
    """Covered fraction of each pixel from ``per_pixel``² samples a pixel, on a grid offset from the pixel's."""
    rows, columns = shape
    hits = covered(centres, radii, samples(size, shape, per_pixel, offset))
    return hits.reshape(rows, per_pixel, columns, per_pixel).mean(axis=(1, 3))


def oracle_print(layers, colours, size, shape, per_pixel=6, offset=0.37):
    """Mean colour of each pixel of inks multiplied at every sample point (not pixel-averaged coverages)."""
    rows, columns = shape
    points = samples(size, shape, per_pixel, offset)
    colour = np.ones((len(points), 3))
    for (centres, radii), ink in zip(layers, colours, strict=True):
        colour *= 1.0 - covered(centres, radii, points)[:, None] * (1.0 - np.asarray(ink))
    return colour.reshape(rows, per_pixel, columns, per_pixel, 3).mean(axis=(1, 3))


def hexagonal(size, spacing, jitter=0.0, rng=None):
    """A hexagonal lattice filling the canvas, optionally jittered by ``jitter * spacing``."""
    width, height = size
    rows = np.arange(0, height / (spacing * np.sqrt(3) / 2))
    points = [
        (x + (0.5 * spacing if i % 2 else 0.0), i * spacing * np.sqrt(3) / 2)
        for i in rows
        for x in np.arange(0.25 * spacing, width, spacing)
    ]
    points = np.array(points) + [0, 0.25 * spacing]
    if jitter:
        points += rng.uniform(-jitter, jitter, points.shape) * spacing
    return points[(points[:, 0] < width) & (points[:, 1] < height) & (points >= 0).all(axis=1)]


@pytest.fixture(scope="module")
def blue_noise():
    """Stipple's own blue noise: 1500 dots of a constant density on a 48 x 48 canvas (unit coordinates)."""
    return stipple.halftone_torus(np.full((48, 48), 0.5), 1500, iterations=60).points % 1.0


def interior(image, margin):
    return image[margin:-margin, margin:-margin]


def test_union_image_is_exact_at_its_sample_points_and_keeps_the_discs_areas(rng):
    centres = rng.uniform(0, 1, (60, 2)) * [20, 14]
    radii = rng.uniform(0.2, 2.5, 60)
    image = union_coverage_image(centres, radii, (20, 14), (21, 40), supersample=3)
    # Exact: each fine pixel is inked iff its centre is inside a disc.
    exact = oracle_image(centres, radii, (20, 14), (21, 40), per_pixel=3, offset=0.5)
    assert np.array_equal(np.round(image * 9), np.round(exact * 9)) and 0 < exact.mean() < 1
    # And close to the true union's area (sampled 12 x 12 a pixel, elsewhere).
    reference = oracle_image(centres, radii, (20, 14), (21, 40), per_pixel=12)
    assert abs(image.mean() - reference.mean()) < 0.01 * reference.mean()
    assert np.abs(image - reference).mean() < 0.02
    # One disc's expected area is its area (Pillow's ellipse draws +10 % at 10 pixels' radius).
    areas = []
    for _ in range(300):
        radius = rng.uniform(0.5, 3.0)
        disc = union_coverage_image(rng.uniform(4, 6, (1, 2)), [radius], (10, 10), (10, 10), supersample=4)
        areas.append(disc.sum() / (np.pi * radius**2))
    assert abs(np.mean(areas) - 1) < 0.01


def test_union_model_matches_blue_noise_discs(blue_noise):
    grid = (np.stack(np.meshgrid(np.arange(600), np.arange(600)), axis=-1).reshape(-1, 2) + 0.37) / 600
    distances, _ = cKDTree(blue_noise, boxsize=1.0).query(grid)  # periodic: the torus, no edges
    for ratio in (0.2, 0.5, 0.8, 1.0, 1.2, 1.5):
        radius = np.sqrt(ratio / (np.pi * len(blue_noise)))
        assert abs(np.mean(distances < radius) - union_coverage(ratio)) < 0.012, ratio
    coverage = np.linspace(0, 0.99, 50)
    assert np.allclose(union_coverage(ink_ratio(coverage)), coverage)
    assert np.all(np.diff(union_coverage(np.linspace(0, 3, 100))) > 0)


@pytest.mark.parametrize("points", ["blue noise", "hexagonal", "jittered"])
@pytest.mark.parametrize("darkness", [0.2, 0.5, 0.9, 1.0])
def test_constant_darkness_is_drawn_at_its_coverage(blue_noise, points, darkness, rng):
    size = (48.0, 48.0)
    if points == "blue noise":
        centres = blue_noise * size
    else:
        centres = hexagonal(size, 1.2, jitter=0.2 if points == "jittered" else 0.0, rng=rng)
    radii = tone_radii(centres, np.full((24, 24), darkness), size)
    drawn = interior(oracle_image(centres, radii, size, (48, 48), per_pixel=6), 4)
    if darkness == 1.0:
        assert drawn.mean() > 0.997  # black comes out black
    else:
        assert abs(drawn.mean() - darkness) < 0.01


def ring(image, k):
    """Mean of the pixels ``k`` pixels in from the image's edges (k = 0: the outermost rows and columns)."""
    return np.r_[image[k], image[-1 - k], image[:, k], image[:, -1 - k]].mean()


@pytest.mark.parametrize("darkness", [0.2, 0.5, 0.9])
def test_a_periodic_canvas_draws_a_torus_picture_without_a_frame(blue_noise, darkness):
    """The torus's dots of a constant density, drawn with their copies across the edges at the radii of the
    periodic canvas: the pixels along the edges have the interior's coverage. On the picture's own canvas with
    the edge dots moved in (``fit_inside``), a dark tone's outermost pixels come out light and the next dark."""
    size = (48.0, 48.0)
    centres = blue_noise * size
    radii = tone_radii(centres, np.full((24, 24), darkness), size, periodic=True)
    copies, origin = wrapped_copies(centres, size, radii.max())
    drawn = oracle_image(copies, radii[origin], size, (48, 48), per_pixel=6)
    assert all(abs(ring(drawn, k) - darkness) < 0.015 for k in range(3))
    assert abs(interior(drawn, 4).mean() - darkness) < 0.01
    if darkness == 0.9:
        flat = tone_radii(centres, np.full((24, 24), darkness), size)
        [(moved, flat)], _ = fit_inside([(centres, flat)], size)
        framed = oracle_image(moved, flat, size, (48, 48), per_pixel=6)
        assert ring(framed, 0) < darkness - 0.05 and ring(framed, 1) > darkness + 0.03


def test_periodic_radii_leave_the_interior_as_the_plain_canvas_does(blue_noise, rng):
    """The periodic canvas only adds copies beyond the edges: far from them the radii are the plain canvas's."""
    size = (48.0, 48.0)
    centres = blue_noise * size
    darkness = gaussian_filter(rng.random((24, 24)), 2, mode="wrap")
    periodic = tone_radii(centres, darkness, size, periodic=True)
    plain = tone_radii(centres, darkness, size)
    inner = np.all((centres > 12) & (centres < 36), axis=1)
    assert np.allclose(periodic[inner], plain[inner], rtol=0.02)


def test_periodic_tone_dots_draw_each_dot_across_the_edges_where_the_picture_wants_ink(blue_noise):
    """One disc per dot where it was placed, at its radius, and a copy of every disc that reaches across an edge
    (for raster pictures); on a page whose left tenth is black and the rest white, a dot just left of the right
    edge (on the torus, next to the black bar) is drawn across the edge, in the bar, not alone on the white."""
    size = (48.0, 48.0)
    centres = blue_noise * size
    (dots,) = periodic_tone_dots([("dots", (0, 0, 0), centres)], size, [np.full((48, 48), 0.5)])
    radii = tone_radii(centres, np.full((48, 48), 0.5), size, periodic=True)
    assert np.array_equal(dots.centres, centres) and np.allclose(dots.radii, radii)
    copies, origin = wrapped_copies(centres, size, radii.max())
    reaching = np.all((copies + radii[origin, None] > 0) & (copies - radii[origin, None] < size), axis=1)
    reaching[: len(centres)] = False
    assert len(dots.copies[0]) == reaching.sum() > 0
    assert np.allclose(np.sort(dots.copies[1]), np.sort(radii[origin][reaching]))
    coverage = np.zeros((48, 48))
    coverage[:, :5] = 1.0
    stray = np.array([[47.9, 24.0]])
    (bar,) = periodic_tone_dots([("dots", (0, 0, 0), np.vstack([centres, stray]))], size, [coverage])
    assert np.allclose(bar.centres[-1], stray - [48.0, 0.0])
    assert not np.any(np.all(np.isclose(bar.copies[0], stray), axis=1))


def test_a_light_gray_edge_across_from_a_dark_one_keeps_its_dots_and_copies(blue_noise):
    """Only near white are copies left out: on a light gray page (0.05) with a dark bar (0.7) along the left edge,
    a dot just left of the right edge was drawn across the edge in the bar, and the bar's copies left out of the
    gray, both counted by the radii where they were placed: the gray's outermost pixels came out 25 % too light."""
    size = (48.0, 48.0)
    coverage = np.full((48, 48), 0.05)
    coverage[:, :5] = 0.7
    edge = np.array([[47.9, 24.0]])
    (dots,) = periodic_tone_dots([("dots", (0, 0, 0), np.vstack([blue_noise * size, edge]))], size, [coverage])
    assert np.allclose(dots.centres[-1], edge)  # drawn where it was placed
    crossing = dots.centres[:, 0] < dots.radii  # the bar's discs across the left edge: drawn in the gray too
    assert crossing.any() and np.sum(dots.copies[0][:, 0] > size[0] / 2) >= crossing.sum()


def test_a_small_dark_mark_on_a_light_page_is_drawn_dark(rng):
    """A 6-pixel mark of darkness 0.95 on a page of 0.03: its dots are 30 times as dense as the page's, and a grid
    of the average's pixels per dot measured them a pixel each (its core came out 0.83 dark)."""
    size = (120.0, 90.0)
    y, x = np.mgrid[0:90, 0:120] + 0.5
    inside = np.hypot(x - 60, y - 45) <= 6
    darkness = np.where(inside, 0.95, 0.03)
    page = hexagonal(size, 5.6, jitter=0.2, rng=rng)
    page = page[np.hypot(page[:, 0] - 60, page[:, 1] - 45) > 7]
    mark = hexagonal((14.0, 14.0), 1.08, jitter=0.2, rng=rng) + [53.0, 38.0]
    mark = mark[np.hypot(mark[:, 0] - 60, mark[:, 1] - 45) <= 6]
    centres = np.vstack([page, mark])
    radii = tone_radii(centres, darkness, size)
    drawn = oracle_image(centres, radii, size, (90, 120), per_pixel=6)
    core = np.hypot(x - 60, y - 45) <= 4
    assert drawn[core].mean() > 0.92
    assert abs(drawn[np.hypot(x - 60, y - 45) > 12].mean() - 0.03) < 0.01


def test_ramp_keeps_every_tenth_of_the_tone_curve():
    columns, rows = 128, 48
    ramp = 1.0 - np.abs(np.arange(columns) + 0.5 - columns / 2) / (columns / 2)  # 0 .. 1 .. 0: periodic
    darkness = np.tile(ramp, (rows, 1))
    centres = stipple.halftone_torus(darkness, 3000, iterations=60).points * [columns, rows]
    radii = tone_radii(centres, darkness, (columns, rows))
    drawn = oracle_image(centres, radii, (columns, rows), (rows, columns), per_pixel=4)
    seen_input = gaussian_filter(1.0 - darkness, 4, mode="reflect")
    seen_output = gaussian_filter(1.0 - drawn, 4, mode="reflect")
    tenth = np.clip((seen_input * 10).astype(int), 0, 9)
    for k in range(10):
        assert abs(seen_output[tenth == k].mean() - seen_input[tenth == k].mean()) < 0.04, k
    assert np.sqrt(np.mean((seen_output - seen_input) ** 2)) < 0.03


def test_light_dots_stay_small_and_apart_and_dark_ones_overlap(blue_noise):
    size = (48.0, 48.0)
    centres = blue_noise * size
    darkness = np.full((48, 48), 0.12)
    darkness[:, 24:] = 0.95
    radii = tone_radii(centres, darkness, size)
    pairs = np.array(sorted(cKDTree(centres).query_pairs(2 * radii.max()))).reshape(-1, 2)
    gap = np.linalg.norm(centres[pairs[:, 0]] - centres[pairs[:, 1]], axis=1) - radii[pairs].sum(axis=1)
    light = (centres[pairs, 0] < 22).all(axis=1)
    dark = (centres[pairs, 0] > 26).all(axis=1)
    assert np.all(gap[light] > 0)  # no two light dots touch
    assert np.mean(gap[dark] < 0) > 0.5  # most dark neighbours overlap
    # Inside the light half, each dot is the disc of 12 % of its cell (blue noise: cells of about 1/M each).
    alone = np.sqrt(0.12 * size[0] * size[1] / (np.pi * len(centres)))
    inside = np.all((centres > 3) & (centres < [20, 45]), axis=1)
    assert np.all(np.abs(radii[inside] / alone - 1) < 0.25) and abs(np.median(radii[inside]) / alone - 1) < 0.03


def test_radii_bounds_hold(blue_noise):
    size = (48.0, 48.0)
    centres = blue_noise * size
    darkness = np.linspace(0, 1, 48)[None, :].repeat(48, axis=0)
    radii = tone_radii(centres, darkness, size, min_radius=0.1, max_radius=0.8, max_ratio=0.6)
    nearest, _ = cKDTree(centres).query(centres, k=2)
    assert radii.min() >= 0.1 and radii.max() <= 0.8
    assert np.all(radii <= np.maximum(0.6 * nearest[:, 1], 0.1) + 1e-12)
    assert len(tone_radii(np.zeros((0, 2)), darkness, size)) == 0
    white = tone_radii(centres, np.zeros((8, 8)), size, passes=3)
    assert white.max() < 0.01  # nothing to draw: the dots vanish
    # A dot given twice is drawn like one dot, not capped to nothing by its twin at distance 0.
    twice = tone_radii(np.vstack([centres, centres[:1]]), np.full((8, 8), 0.5), size)
    once = tone_radii(centres, np.full((8, 8), 0.5), size)
    assert twice[0] == twice[-1] and abs(twice[0] / once[0] - 1) < 0.1


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda c, d: tone_radii(c, d, (10, 10), passes=-1), r"passes must be an integer in \[0, 50\]"),
        (lambda c, d: tone_radii(c, d, (10, 10), max_ratio=0), r"max_ratio must be in \(0, 10\]"),
        (lambda c, d: tone_radii(c, d, (10, 10), min_radius=-1), "min_radius must be a finite number >= 0"),
        (lambda c, d: tone_radii(c, d, (10, 10), max_radius=0), "max_radius must be a finite number > 0"),
        (lambda c, d: tone_radii(c, d, (10, 10), samples_per_dot=2), r"samples_per_dot must be .* \[4, 1024\]"),
        (lambda c, d: tone_radii(c, d + 1, (10, 10)), r"darkness must be finite and in \[0, 1\]"),
        (lambda c, d: tone_radii(c[:, :1], d, (10, 10)), r"centres must have shape \(N, 2\)"),
        (lambda c, d: tone_radii(c, d, (10, 0)), "size must be .* two positive numbers"),
        (lambda c, d: tone_radii_layers([(c, d)], (10, 10), colours=[(0, 0)]), "colours must be 1 RGB triples"),
        (lambda c, d: multiply_separation(np.ones((2, 2, 3)), "rgb"), "separation must be one of cmyk, cmy, gray"),
        (lambda c, d: union_coverage_image(c, -np.ones(len(c)), (10, 10), (5, 5)), "radii must be finite and >= 0"),
        (lambda c, d: fit_inside([(c, np.ones(len(c)))], (10, 10), how="wrap"), "how must be one of clamp, scale"),
    ],
)
def test_bad_arguments_name_the_parameter_and_range(call, message, rng):
    with pytest.raises(StippleError, match=message):
        call(rng.uniform(0, 10, (20, 2)), np.full((5, 5), 0.5))


def test_fit_inside_keeps_dots_on_the_canvas_and_the_tone(blue_noise, rng):
    size = (48.0, 32.0)
    centres = blue_noise * size
    radii = rng.uniform(0.2, 1.5, len(centres))
    (moved, same), margin = fit_inside([(centres, radii)], size)[0][0], 0.0
    assert np.all(moved - same[:, None] >= 0) and np.all(moved + same[:, None] <= size)
    shift = np.abs(moved - centres)
    assert np.all(shift <= radii[:, None])
    away = np.all((centres > 1.5) & (centres < np.subtract(size, 1.5)), axis=1)
    assert np.all(shift[away] == 0) and np.any(shift > 0)
    [(scaled, smaller)], margin = fit_inside([(centres, radii)], size, how="scale")
    assert margin == pytest.approx(radii.max())
    assert np.all(scaled - smaller[:, None] >= -1e-9) and np.all(scaled + smaller[:, None] <= np.add(size, 1e-9))
    before = oracle_image(centres, radii, size, (32, 48), per_pixel=4).mean()
    inner = (slice(round(margin * 4), -round(margin * 4)),) * 2
    after = oracle_image(scaled, smaller, size, (128, 192), per_pixel=1)[inner].mean()
    assert abs(after - before) < 0.01  # the scaled copy keeps the ink's share


def test_multiply_separation_prints_the_image_and_additive_one_does_not(rng):
    rgb = rng.uniform(0, 1, (16, 16, 3))
    for separation in ("cmyk", "cmy"):
        inks = multiply_separation(rgb, separation)
        assert all(0 <= a.min() and a.max() <= 1 for _, _, a in inks)
        assert np.allclose(multiply_colour([a for _, _, a in inks], [c for _, c, _ in inks]), rgb)
    ((_, _, black),) = multiply_separation(rgb, "gray")
    assert np.allclose(black, 1 - rgb @ [0.299, 0.587, 0.114])
    # stipple.colour.separate's coverages add; printed over each other they come out lighter.
    red = np.full((1, 1, 3), (0.7, 0.1, 0.1))
    layers = separate(red, "cmyk")
    printed = multiply_colour([layer.density for layer in layers], [layer.colour for layer in layers])
    assert printed[0, 0, 0] == pytest.approx(0.7) and np.all(printed[0, 0, 1:] > 0.25)  # green, blue: 0.28, not 0.1


def test_layers_without_colours_are_inks_alone_and_one_ink_prints_its_coverage(blue_noise, rng):
    size = (48.0, 48.0)
    darkness = rng.uniform(0, 1, (6, 6))
    first, second = blue_noise[::2] * size, blue_noise[1::2] * size
    radii = tone_radii_layers([(first, darkness), (second, 1 - darkness)], size)
    assert np.array_equal(radii[0], tone_radii(first, darkness, size))
    assert np.array_equal(radii[1], tone_radii(second, 1 - darkness, size))
    one = multiply_picture([(first, radii[0])], [(0.2, 0.4, 0.6)], size, (24, 24), paper=(1.0, 0.9, 0.8))
    coverage = union_coverage_image(first, radii[0], size, (24, 24))
    assert np.allclose(one, [1.0, 0.9, 0.8] * (1 - coverage[..., None] * [0.8, 0.6, 0.4]), atol=1e-6)


@pytest.fixture(scope="module")
def two_colours():
    """Jointly stippled inks of a 48 x 32 image: an orange half and a teal half."""
    rgb = np.zeros((32, 48, 3))
    rgb[:, :24] = (0.85, 0.45, 0.2)
    rgb[:, 24:] = (0.15, 0.45, 0.5)
    layers, problem, result = halftone_colour(rgb, 2500, iterations=60)
    centres = [result.points[part] * [48, 32] for part in problem.slices]
    return rgb, layers, centres


@pytest.mark.parametrize("start", ["separate", "multiply"])
def test_joint_inks_print_the_image_colour(two_colours, start):
    rgb, layers, centres = two_colours
    if start == "separate":
        coverages, colours = [layer.density for layer in layers], [layer.colour for layer in layers]
    else:
        inks = {name: (colour, a) for name, colour, a in multiply_separation(rgb)}
        coverages, colours = [inks[layer.name][1] for layer in layers], [inks[layer.name][0] for layer in layers]
    radii = tone_radii_layers(list(zip(centres, coverages, strict=True)), (48, 32), colours=colours, target=rgb)
    printed = oracle_print(list(zip(centres, radii, strict=True)), colours, (48, 32), (32, 48))
    for half in (slice(4, 20), slice(28, 44)):
        mean = printed[4:-4, half].mean(axis=(0, 1))
        assert np.all(np.abs(mean - rgb[0, half.start]) < 0.015), (mean, rgb[0, half.start])
    # The multiply renderer is exact at its sample points (to its 8-bit colour table).
    drawn = list(zip(centres, radii, strict=True))
    picture = multiply_picture(drawn, colours, (48, 32), (32, 48), supersample=6)
    assert np.abs(picture - oracle_print(drawn, colours, (48, 32), (32, 48), offset=0.5)).max() <= 0.5 / 255 + 1e-6


def test_a_periodic_picture_whose_grid_reaches_the_bound_is_drawn(blue_noise, monkeypatch):
    """A million dots asked for an analysis grid at ``MAX_GRID_PIXELS`` and the periodic canvas around it was
    refused as too large to draw, after the whole run. Here the bound is lowered to reach it with 1500 dots."""
    import stipple.tone.radii as radii_module
    import stipple.tone.raster as raster_module

    bound = 1 << 14
    monkeypatch.setattr(radii_module, "MAX_GRID_PIXELS", bound)
    monkeypatch.setattr(raster_module, "MAX_GRID_PIXELS", bound)
    size = (48.0, 48.0)
    radii = tone_radii(blue_noise * size, np.full((48, 48), 0.5), size, periodic=True)
    drawn = oracle_image(blue_noise * size, radii, size, (48, 48), per_pixel=4)
    assert abs(drawn.mean() - 0.5) < 0.02


def test_an_ink_of_few_dots_does_not_ask_for_the_grid_of_all_dots_at_its_density(blue_noise, monkeypatch):
    """The joint grid gives every ink's densest dots half the average's pixels; a few dots of one ink in a small
    mark (about 200 times that ink's mean density) once sized the grid as if all the dots were that dense."""
    import stipple.tone.radii as radii_module

    asked = []
    grid = radii_module._grid
    monkeypatch.setattr(radii_module, "_grid", lambda *args: asked.append(grid(*args)) or asked[-1])
    size = (48.0, 48.0)
    y, x = np.mgrid[0:48, 0:48] + 0.5
    mark = np.where(np.hypot(x - 24, y - 24) <= 1.5, 0.9, 0.0)
    few = np.array([[23.5, 23.5], [24.5, 24.5], [23.5, 24.5], [24.5, 23.5]])
    layers = [(blue_noise * size, np.full((48, 48), 0.5)), (few, mark)]
    tone_radii_layers(layers, size, colours=[(0, 1, 1), (0, 0, 0)], passes=0, periodic=True)
    (rows, columns), dots = asked[0], len(blue_noise) + len(few)
    assert rows * columns <= 24 * dots * 1.05, (rows * columns) / dots


def test_a_flat_light_page_gets_even_dots():
    """A light tone's dot is about one analysis-grid pixel across: drawn at 2 x 2 fine pixels its area was off by
    a fine pixel or two and the corrections fitted that noise (radii 10.5 % apart, 2.1 x largest to smallest),
    where the cells' areas differ by under 3 %."""
    from stipple.torus import halftone_torus

    darkness = np.full((120, 160), 0.03)
    centres = halftone_torus(darkness, 1500, threads=1, seed=0).points * [160, 120]
    radii = tone_radii(centres, darkness, (160, 120), periodic=True)
    assert radii.std() / radii.mean() < 0.065 and radii.max() / radii.min() < 1.6


@pytest.mark.parametrize("width, count", [(40, 100), (600, 150)])
def test_a_strip_two_pixels_high_keeps_its_tone(width, count):
    """The periodic canvas's margin was at most 0.15 of a side: less than a dot spacing on a strip a few dots high,
    whose edge dots then had no neighbours across the edges, grew, and drew a 0.5 gray as 0.47. With fewer dots
    than the strip is long over high, one spacing is more than its height: such a margin's outer part had
    darkness but no dots (0.434)."""
    from stipple.torus import halftone_torus

    darkness = np.full((2, width), 0.5)
    centres = halftone_torus(darkness, count, threads=1, seed=0).points * [width, 2]
    radii = tone_radii(centres, darkness, (width, 2), periodic=True)
    copies, origin = stipple.tone.wrap.wrapped_copies(centres, (width, 2), np.array([width, 2.0]))
    drawn = union_coverage_image(copies, radii[origin], (width, 2), (8, 4 * width), supersample=4)
    assert abs(drawn.mean() - 0.5) < 0.015, drawn.mean()


def test_a_sparse_ink_keeps_the_wrapped_margin_at_its_cap():
    """The floor of one spacing is of all the dots, not of the sparsest ink: a colour photo's cyan of 3 dots widened
    the canvas to about five pictures (its command 17.7 -> 23 s, 0.5 -> 1 GiB), where 0.15 of each side is enough."""
    from stipple.tone.wrap import MAX_WRAP_SHARE, wrap_shares

    assert wrap_shares((300, 200), True, 3, 30000) == (MAX_WRAP_SHARE, MAX_WRAP_SHARE)
    share_x, share_y = wrap_shares((600, 3), True, 1500, 1500)  # a strip: one spacing, more than 0.15 of 3 px
    assert share_x == pytest.approx(3 * np.sqrt(1.2) / 600) and share_y == pytest.approx(np.sqrt(1.2) / 3)
    assert wrap_shares((600, 2), True, 150, 150)[1] == 1.0  # one spacing, 2.8 px, more than the side
