"""Drawing defaults: dots that never touch, stay on the canvas, --invert as white on black, and the globe."""

import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image
from scipy.spatial import cKDTree

from stipple.cli import main
from stipple.errors import StippleError
from stipple.render.dots import capped_radii, flat_dots, inset
from stipple.render.pen import dot_paths

PORTRAIT = Path(__file__).resolve().parent.parent / "samples" / "astronaut256.png"


def run(args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    assert result.exit_code == 0, result.output
    return result


def circles(path, copies=False):
    """``(x, y, r)`` rows of the SVG's circles: the dots', with ``copies`` their copies across a wrapping page's
    edges too."""
    end = "" if copies else "/>"
    found = re.findall(r'<circle cx="([-0-9.]+)" cy="([-0-9.]+)" r="([-0-9.]+)"' + end, Path(path).read_text())
    return np.array(found, dtype=float)


def radius_over_spacing(table):
    """Each dot's radius over its distance to the nearest other dot on the drawing."""
    distances, _ = cKDTree(table[:, :2]).query(table[:, :2], k=2)
    return table[:, 2] / distances[:, 1]


def test_plotter_style_leaves_neighbours_apart_on_the_portrait(tmp_path):
    run(["torus", PORTRAIT, "-M", 3000, "--iterations", 15, "--style", "plotter", "-q", "-o", tmp_path / "p.svg"])
    table = circles(tmp_path / "p.svg")
    ratio = radius_over_spacing(table)
    assert len(table) == 3000 and np.mean(ratio < 0.5) >= 0.99 and ratio.max() <= 0.45 + 1e-3
    # The cap only bites where dots are close: the light regions keep the tone radius (the largest one).
    assert np.mean(table[:, 2] >= table[:, 2].max() - 1e-3) > 0.1
    inside = (table[:, :2] - table[:, 2:] >= 0) & (table[:, :2] + table[:, 2:] <= 256)
    assert inside.all()


def test_a_dot_across_the_edge_from_a_black_bar_is_drawn_in_the_bar_in_both_styles(tmp_path):
    """On the torus a dot just left of the right edge may belong to a black bar along the left edge: on a white
    right edge it would stand alone (the plotter style drew it whole on the paper's white margin)."""
    page = np.full((40, 60), 255, dtype=np.uint8)
    page[:, :6] = 0
    Image.fromarray(page).save(tmp_path / "bar.png")
    bar = np.column_stack([np.repeat((np.arange(4) + 0.5) * 1.5, 20), np.tile((np.arange(20) + 0.5) * 2, 4)])
    stray = [59.95, 21.0]
    with open(tmp_path / "dots.csv", "w") as table:
        table.write("x,y\n" + "".join(f"{x},{y}\n" for x, y in [*bar, stray]))
    for style in ("plotter", "tone"):
        svg = tmp_path / f"{style}.svg"
        run(["render", tmp_path / "dots.csv", "--like", tmp_path / "bar.png", "--style", style, "-o", svg])
        assert len(circles(svg)) == len(bar) + 1
        assert not np.any(circles(svg, copies=True)[:, 0] > 30), style  # nothing on the white half


def test_uniform_sphere_is_not_a_black_disc(tmp_path):
    outputs = ["-o", tmp_path / "map.svg", "-o", tmp_path / "globe.png"]
    run(["sphere", "--uniform", "-M", 2000, "--iterations", 15, "--projection", "equirect", "-q", *outputs])
    table = circles(tmp_path / "map.svg")
    assert len(table) == 2000  # equirect: every dot, none dropped
    assert np.mean(radius_over_spacing(table) < 0.5) >= 0.99
    assert np.all(table[:, :2] - table[:, 2:] >= 0) and np.all(table[:, :2] + table[:, 2:] <= [2000, 1000])
    run(["sphere", "--uniform", "-M", 2000, "--iterations", 15, "-q", "-o", tmp_path / "globe.png"])
    gray = np.asarray(Image.open(tmp_path / "globe.png").convert("L"), dtype=float)
    y, x = np.mgrid[: gray.shape[0], : gray.shape[1]]
    r = np.hypot(x - gray.shape[1] / 2, y - gray.shape[0] / 2) / (0.49 * gray.shape[0])
    centre, limb = gray[r < 0.5].mean(), gray[(r > 0.85) & (r < 0.97)].mean()
    assert 60 < centre < 200 and abs(limb - centre) < 0.1 * centre  # grey, and foreshortening keeps the limb's tone


def test_orthographic_svg_counts_the_visible_side(tmp_path):
    run(["sphere", "--uniform", "-M", 500, "--iterations", 3, "-q", "-o", tmp_path / "g.svg", "--view", "30,40"])
    svg = (tmp_path / "g.svg").read_text()
    shown = svg.count("<ellipse")
    assert 200 < shown < 300 and f"{shown} of 500 dots on the visible side" in svg


@pytest.fixture
def ramp(tmp_path):
    """Dark on the left, light on the right."""
    pixels = np.tile(np.linspace(20, 235, 48).astype(np.uint8), (32, 1))
    path = tmp_path / "ramp.png"
    Image.fromarray(pixels).save(path)
    return path


def test_invert_draws_light_dots_on_black_where_the_image_is_light(ramp, tmp_path):
    run(["torus", ramp, "-M", 400, "--iterations", 10, "--invert", "-q", "-o", tmp_path / "i.png"])
    gray = np.asarray(Image.open(tmp_path / "i.png").convert("L"), dtype=float)
    assert gray.min() == 0 and gray.max() == 255  # white dots on black paper
    left, right = gray[:, : gray.shape[1] // 3], gray[:, -gray.shape[1] // 3 :]
    assert right.mean() > left.mean() + 20  # the light side of the image is the light side of the picture
    # Tone-true: each third of the picture is as light as that third of the ramp (20 ... 235).
    thirds = np.array_split(np.linspace(20, 235, 48), 3)
    assert abs(left.mean() - thirds[0].mean()) < 15 and abs(right.mean() - thirds[2].mean()) < 15


def test_background_and_colour_for_any_pair(ramp, tmp_path):
    args = ["torus", ramp, "-M", 200, "--iterations", 3, "-q", "--background", "navy", "--color", "#ffe000"]
    run(args + ["-o", tmp_path / "c.png", "-o", tmp_path / "c.svg"])
    rgb = np.asarray(Image.open(tmp_path / "c.png").convert("RGB"), dtype=float)
    corner_colours = {tuple(rgb[0, 0]), tuple(rgb[-1, -1])}
    assert (0, 0, 128) in corner_colours or rgb[..., 2].max() == 128  # navy paper
    assert np.any((rgb[..., 0] > 200) & (rgb[..., 1] > 180) & (rgb[..., 2] < 80))  # yellow dots
    svg = (tmp_path / "c.svg").read_text()
    assert 'fill="#000080"' in svg and 'fill="#ffe000"' in svg
    result = CliRunner().invoke(main, ["torus", str(ramp), "-M", "20", "--color", "blurple", "-q"])
    assert result.exit_code == 1 and "color must be a colour" in result.output


def test_no_dot_crosses_the_edge_with_a_large_radius_or_a_pen(ramp, tmp_path):
    common = ["torus", ramp, "-M", 300, "--iterations", 3, "-q", "--width", "48mm"]
    run(common + ["--dot-radius", "1.5mm", "-o", tmp_path / "big.svg"])
    table = circles(tmp_path / "big.svg")
    assert np.allclose(table[:, 2], 1.5) and np.all(table[:, :2] - 1.5 >= 0) and np.all(table[:, :2] + 1.5 <= [48, 32])
    run(common + ["--dot-style", "filled", "--pen-width", "0.4mm", "-o", tmp_path / "pen.svg"])
    coordinates = re.findall(
        r"([-0-9.]+),([-0-9.]+)", " ".join(re.findall(r'd="([^"]+)"', (tmp_path / "pen.svg").read_text()))
    )
    vertices = np.array(coordinates, dtype=float)
    assert len(vertices) > 300 and np.all(vertices - 0.2 >= -1e-3) and np.all(vertices + 0.2 <= [48.001, 32.001])


def test_copies_of_a_position_keep_one_dot_and_their_nearest_distance_is_zero():
    """Copies of one point are one point (5 million of them kept ``stipple render`` busy for over 10 minutes, their
    pairs growing as the square of their count; a hostile review; bench/hostile_sweep.py times it). The direct
    distances of the distinct points are the oracle."""
    from stipple.render.dots import nearest_distances, thin_apart

    distinct = np.random.default_rng(5).random((300, 2)) * 10
    centres = np.concatenate([distinct[:150], np.full((3000, 2), 5.0), distinct[150:]])
    distances = np.hypot(*(distinct[:, None] - distinct[None, :]).transpose(2, 0, 1)) + np.eye(300) * 1e9
    direct = np.minimum(distances.min(axis=1), np.hypot(*(distinct - 5.0).T))
    nearest = nearest_distances(centres)
    assert np.all(nearest[150:3150] == 0.0)
    np.testing.assert_allclose(np.concatenate([nearest[:150], nearest[3150:]]), direct, rtol=1e-12)
    kept = thin_apart(centres, 0.5)
    assert kept[150:3150].sum() <= 1 and kept[3149] == kept[150:3150].any()  # the last copy, if any
    free = np.concatenate([kept[:150], kept[3150:]])
    assert np.array_equal(
        free, thin_apart(np.concatenate([distinct[:150], [[5.0, 5.0]], distinct[150:]]), 0.5)[np.r_[0:150, 151:301]]
    )


@pytest.mark.parametrize("style", ["point", "circle", "filled"])
def test_no_pen_dot_inks_past_the_page_edge_whatever_its_style(style):
    """A "point" is a stroke a tenth of the pen long, so the smallest pen dots ink 0.55-0.6 of the pen from their
    centres: with a margin of half the pen they crossed the edge (0.05 mm over with a 0.5 mm pen)."""
    size, pen = np.array([40.0, 30.0]), 1.0
    corners = np.array([[0.0, 0.0], [40.0, 0.0], [0.0, 30.0], [40.0, 30.0], [20.0, 15.0]])
    (dots,) = flat_dots([("dots", "black", corners)], tuple(size), tone_radius=0.2, pen=pen, dot_style=style)
    vertices = np.concatenate(
        [np.column_stack([z.real, z.imag]) for z in dot_paths(dots.centres, dots.radii, style, pen)]
    )
    assert len(dots.centres) == 5
    assert np.all(vertices - pen / 2 >= -1e-9) and np.all(vertices + pen / 2 <= size + 1e-9)


def test_capped_radii_and_inset_rules():
    np.testing.assert_allclose(capped_radii([1.0, 4.0, 10.0], 2.0), [0.45, 1.8, 2.0])
    moved, margin = inset(np.array([[0.0, 0.0], [10.0, 5.0]]), (10.0, 5.0), 1.0)
    np.testing.assert_allclose(moved, [[1.0, 1.0], [9.0, 4.0]])
    assert margin == 1.0


@pytest.mark.parametrize(
    "style, area",
    [
        (["--dot-style", "point"], np.pi / 4 + 0.1),  # a stroke a tenth of the pen long, round caps
        (["--dot-style", "circle", "--dot-radius", "2mm"], np.pi * (2**2 - 1**2)),  # a ring one pen wide
    ],
)
def test_a_pen_preview_inks_the_area_its_svg_strokes(tmp_path, style, area):
    """The PNG preview of pen paths inks what the SVG's strokes ink (round caps included): a 1 mm pen on a page of
    1 mm user units, 25 dots far apart. Pillow's lines (width rounded to whole pixels, caps a pixel short) drew
    a point pen 3 % lighter than its SVG."""
    lattice = (np.arange(5) + 0.5) * 10
    dots = tmp_path / "dots.csv"
    dots.write_text("x,y\n" + "".join(f"{x},{y}\n" for x in lattice for y in lattice))
    png = tmp_path / "pen.png"
    arguments = ["render", dots, "--size", "50,50", "--width", "50mm", "--pen-width", "1mm", "--png-width", 500]
    result = run([*arguments, *style, "-o", png])
    assert result.exit_code == 0, result.output
    ink = 1 - np.asarray(Image.open(png).convert("L"), dtype=float) / 255
    assert ink.sum() / 100 == pytest.approx(25 * area, rel=0.01)  # 10 × 10 pixels a mm²


def test_thin_apart_keeps_a_maximal_set_at_the_distance():
    from stipple.render.dots import thin_apart

    centres = np.random.default_rng(4).random((600, 2)) * 10
    kept = thin_apart(centres, 0.5)
    distances = np.hypot(*(centres[:, None] - centres[None, :]).transpose(2, 0, 1)) + np.eye(600) * 1e9
    assert distances[np.ix_(kept, kept)].min() >= 0.5  # no two kept dots closer
    assert np.all(distances[np.ix_(~kept, kept)].min(axis=1) < 0.5)  # every dot left out had a kept one that close
    assert 0 < (~kept).sum() < 600
    assert thin_apart(centres, 1e-6).all()


@pytest.mark.parametrize("style", ["point", "circle", "filled"])
def test_pen_dots_never_touch_in_the_darkest_tones(tmp_path, style):
    """A dark image drawn with a pen: where the stipple's dots are closer than the pen's smallest dot allows, they
    touched (15001 overlapping pairs of point dots at -M auto on a dark photo); they are left out now."""
    from stipple.render.flat import torus_drawing

    points = np.random.default_rng(0).random((6000, 2))  # clumpy: many pairs far closer than the pen allows
    options = dict(width=(60.0, "mm"), dot_style=style, pen_width=(0.4, "mm"), ink=0.6, style="plotter")
    drawing = torus_drawing(points, (60, 90), **options)
    (dots,) = drawing.layers
    # Every dot's ink as drawn: the union of pen-wide discs along its path. Two dots touch when a vertex of one
    # path comes within a pen width of a vertex of the other (the paths' vertices are at most a few hundredths
    # of the pen apart along them).
    pen = drawing.pen_width
    vertices = np.concatenate([np.column_stack([path.real, path.imag]) for path in dots.paths])
    owner = np.repeat(np.arange(len(dots.paths)), [len(path) for path in dots.paths])
    close = cKDTree(vertices).query_pairs(pen * 1.0, output_type="ndarray")
    assert not np.any(owner[close[:, 0]] != owner[close[:, 1]]), "two pen dots' ink touches"
    assert 1000 < len(dots.centres) < 6000 and any("left out" in note for note in drawing.notes)


def test_the_globe_is_outlined_not_painted_gray(tmp_path):
    """The orthographic PNG painted the whole globe 8 % gray under the dots: a map's empty parts came out gray
    (235) and its light tones darker than the map's. Now a ring marks the edge and the empty parts stay white."""
    lat = np.radians(90 - (np.arange(90) + 0.5) * 2)[:, None]
    lon = np.radians((np.arange(180) + 0.5) * 2)[None, :]
    cosine = np.sin(lat) * 0.5 + np.cos(lat) * 0.866 * np.cos(lon - np.radians(60))
    np.save(tmp_path / "peak.npy", np.exp(-((np.degrees(np.arccos(np.clip(cosine, -1, 1))) / 15) ** 2)))
    picture = tmp_path / "globe.png"
    run(["sphere", tmp_path / "peak.npy", "-M", 1500, "--iterations", 10, "--view", "60,30", "-q", "-o", picture])
    gray = np.asarray(Image.open(picture).convert("L"), dtype=float)
    y, x = np.mgrid[: gray.shape[0], : gray.shape[1]]
    r = np.hypot(x - gray.shape[1] / 2, y - gray.shape[0] / 2) / (0.49 * gray.shape[0])
    far_side = (r > 0.8) & (r < 0.95)  # about 70 degrees from the peak: no dots there
    assert np.median(gray[far_side]) == 255
    assert gray[(r > 0.98) & (r < 1.03)].min() < 230  # the ring


def pen_sphere_drawing(count, projection, style, pen_mm):
    """A 100 mm plotter drawing of ``count`` even dots on the sphere with a pen ``pen_mm`` wide: the drawing, its
    one layer of dots and their pen paths' vertices."""
    from stipple.design import fibonacci_lattice
    from stipple.render.globe import sphere_drawing

    points = fibonacci_lattice(count, np.random.default_rng(1), jitter=0.2)
    lon_lat = (np.degrees(np.arctan2(points[:, 1], points[:, 0])), np.degrees(np.arcsin(points[:, 2])))
    options = dict(width=(100.0, "mm"), dot_style=style, pen_width=(pen_mm, "mm"), style="plotter")
    drawing = sphere_drawing(points, lon_lat, projection=projection, **options)
    (dots,) = drawing.layers
    return drawing, dots, np.concatenate([np.column_stack([path.real, path.imag]) for path in dots.paths])


@pytest.mark.parametrize("projection", ["ortho", "equirect"])
@pytest.mark.parametrize("style", ["point", "circle", "filled"])
def test_pen_dots_never_touch_on_the_globe(style, projection):
    """Foreshortening brings dots near the limb closer but not the pen's width: 23 / 609 / 607 touching pairs of
    point / circle / filled dots on an orthographic globe of 3000 even dots with a 0.4 mm pen, 100 mm wide. The
    map was not thinned at all (a held-out sweep: 24 touching pairs of point dots)."""
    drawing, dots, vertices = pen_sphere_drawing(3000, projection, style, 0.4)
    assert not inks_touch(drawing, dots, vertices), "two pen dots' ink touches"
    assert len(dots.centres) > (1200 if projection == "ortho" else 2400)


def inks_touch(drawing, dots, vertices):
    """Whether two pen dots' paths come closer than the pen's width."""
    owner = np.repeat(np.arange(len(dots.paths)), [len(path) for path in dots.paths])
    close = cKDTree(vertices).query_pairs(drawing.pen_width, output_type="ndarray")
    return bool(np.any(owner[close[:, 0]] != owner[close[:, 1]]))


@pytest.mark.parametrize("projection", ["ortho", "equirect"])
@pytest.mark.parametrize("style", ["point", "circle", "filled"])
def test_pen_dots_on_the_globe_and_the_map_stay_on_the_page(style, projection):
    """The map inset its dots by their radius only and the globe not at all: a 5 mm pen on a 100 mm globe of 500
    dots inked 1.4 mm past its edge, the map 0.8 mm past its with a 1.5 mm pen."""
    drawing, dots, vertices = pen_sphere_drawing(500, projection, style, 5.0)
    half_pen = drawing.pen_width / 2
    assert len(dots.paths) > 50 and not inks_touch(drawing, dots, vertices)
    assert np.all(vertices - half_pen >= -1e-9) and np.all(vertices + half_pen <= np.array(drawing.size) + 1e-9)


def test_a_pen_too_wide_for_the_globe_is_refused_in_one_line():
    """A 90 mm pen on a 100 mm globe: the globe made smaller to fit its dots turned inside out (a traceback)."""
    with pytest.raises(StippleError, match="the pen is too wide for the globe"):
        pen_sphere_drawing(10, "ortho", "point", 90.0)


@pytest.mark.parametrize("stroke", [0.9, 1.3397, 2.15])
@pytest.mark.parametrize("pixels_wide", [240, 413])
def test_a_line_inks_the_area_of_its_stroke_at_any_width(stroke, pixels_wide):
    """A closed square of side 40 (turned 0.3 rad: no edge along the pixels) stroked ``stroke`` wide with round
    joins inks ``4 s w - (4 - pi) w^2 / 4``, the SVG's area, at any PNG width; the discs along it are short by
    less than 0.5 %. Pillow's lines, their width rounded to a quarter pixel, were off by -3.7 to +0.1 % here, and
    ``stipple line``'s tone-true stroke laid down 4-7 % too much ink (a held-out review)."""
    from stipple.io.png import render_line

    side, size = 40.0, (60, 60)
    corners = 30 + 30j + (np.array([-1 - 1j, 1 - 1j, 1 + 1j, -1 + 1j]) * side / 2) * np.exp(0.3j)
    picture = render_line(np.column_stack([corners.real, corners.imag]), size, pixels_wide, stroke)
    drawn = (1 - np.asarray(picture, dtype=float) / 255).mean() * size[0] * size[1]
    assert drawn == pytest.approx(4 * side * stroke - (4 - np.pi) * stroke**2 / 4, rel=0.006)


def test_the_tone_stroke_inks_the_mean_darkness_where_the_line_crosses_itself():
    """``ink W H / length`` alone ignores the ink that crossings and touching strokes share: a wandering closed
    line of 4000 vertices drawn for 0.4 of a 120 x 80 image laid down 0.31; the stroke corrected by the drawn
    line's own ink lays down the 0.4 asked for."""
    from stipple.io.png import render_line
    from stipple.render.flat import tone_stroke
    from stipple.render.pen import closed_length

    t = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    x = 60 + 50 * np.sin(3 * t) * np.cos(t / 2) + 5 * np.sin(17 * t)
    y = 40 + 35 * np.sin(2 * t + 0.3) + 4 * np.cos(23 * t)
    pixels = np.stack([x, y], axis=1)

    def drawn(stroke):
        return 1 - np.asarray(render_line(pixels, (120, 80), 480, stroke), dtype=float).mean() / 255

    assert drawn(0.4 * 120 * 80 / closed_length(pixels)) < 0.35
    assert drawn(tone_stroke(pixels, (80, 120), 0.4)) == pytest.approx(0.4, abs=0.01)


def test_a_very_tall_image_gets_a_narrower_default_png_not_a_huge_one(tmp_path):
    """The default PNG is at least 1024 px wide, but at most ``TALLEST`` times as tall as a square picture's side:
    a 3 x 512 strip was drawn 1024 x 174763 pixels (5.4 GB, a file Pillow then refuses to open)."""
    from stipple.io.png import TALLEST, default_png_width

    assert default_png_width(30150) == default_png_width(30150, (256, 256)) == 1024
    assert default_png_width(10**6, (1024, 1024)) == 4000
    assert default_png_width(1000, (512, 1536)) == 1024  # a 1:3 image keeps the square's width
    assert default_png_width(1000, (3, 512)) == TALLEST * 1024 * 3 // 512
    Image.fromarray(np.full((512, 3), 90, dtype=np.uint8)).save(tmp_path / "strip.png")
    result = CliRunner().invoke(
        main, ["torus", str(tmp_path / "strip.png"), "-M", "300", "-q", "-o", str(tmp_path / "s.png")]
    )
    assert result.exit_code == 0, result.output
    with Image.open(tmp_path / "s.png") as picture:
        assert picture.size == (24, TALLEST * 1024)


def _ink_centroid(picture, size):
    """The ink's centroid of a white-paper PNG picture, in the user units of a canvas of ``size`` stretched onto
    the picture's whole frame (as ``stipple evaluate`` maps a picture onto its input)."""
    ink = 1 - np.asarray(picture, dtype=np.float64) / 255
    rows, columns = ink.shape
    y, x = np.mgrid[0:rows, 0:columns] + 0.5
    return np.array([(ink * x).sum() * size[0] / columns, (ink * y).sum() * size[1] / rows]) / ink.sum()


@pytest.mark.parametrize("blend", ["over", "multiply"])
def test_a_png_maps_the_canvas_onto_its_whole_frame(blend):
    """A 480 x 160 canvas drawn 1024 wide is 341.33 pixels high: the PNG has 341 whole rows and the canvas fills
    them, so a dot near the bottom is where the frame puts it. With one scale for both axes the canvas filled
    341.25 of 342 rows (the last one part paper) and the dot sat 0.29 user units too high, the line 0.22 (a page
    of text measured 0.0033 instead of 0.0019 at sigma 4 px against its input)."""
    from stipple.io.png import render_line, render_picture
    from stipple.render.dots import Dots

    size, centre = (480, 160), np.array([400.0, 150.0])
    dots = Dots("d", (0.0, 0.0, 0.0), centre[None], np.array([3.0]))
    underlay = None if blend == "over" else (lambda *_: None)
    picture = render_picture([dots], size, 1024, blend=blend, underlay=underlay)
    assert picture.size == (1024, 341)
    assert _ink_centroid(picture, size) == pytest.approx(centre, abs=0.02)
    line = render_line(np.array([[40.0, 150.0], [440.0, 150.0]]), size, 1024, 2.0, closed=False)
    assert line.size == (1024, 341)
    # Pillow strokes whole fine pixels (8.53 a user unit here): within one of them.
    assert _ink_centroid(line, size)[1] == pytest.approx(150.0, abs=0.1)


def test_a_png_less_than_a_pixel_high_is_refused_or_drawn_on_one_row():
    """Fitted to whole pixels, a canvas below half a pixel high would have no row at all: the PNG writers still
    refuse one below 7/8 of a pixel (``check_png_canvas``), and the measuring picture of a very wide line (the
    tone stroke of a 9000 x 2 image, 2048 wide) is drawn on one row instead of failing in Pillow's ``reduce``."""
    from stipple.errors import StippleError
    from stipple.io.png import check_png_canvas, render_line

    for pixels_wide in (200, 400):  # 0.3 and 0.6 pixels high
        with pytest.raises(StippleError, match="less than one pixel high"):
            check_png_canvas((2000, 3), pixels_wide)
    check_png_canvas((2000, 3), 600)  # 0.9 pixels high: one row
    # A canvas that no width fits is not told to use a smaller (or larger) --png-width (a hostile sweep).
    for size in ((1, 2**31 - 1), (2**31 - 1, 1)):
        with pytest.raises(StippleError, match="too narrow for any PNG .* use SVG"):
            check_png_canvas(size, 16)
    check_png_canvas((1, 60000), 1)  # 60000 pixels high, 1 wide: drawn
    line = render_line(np.array([[10.0, 1.0], [8990.0, 1.0]]), (9000, 2), 2048, 1.0, closed=False)
    assert line.size == (2048, 1)
    assert np.asarray(line).min() < 255


@pytest.mark.parametrize(
    "colours", [["--invert", "--background", "white"], ["--background", "#fff", "--color", "white"]]
)
def test_dots_the_colour_of_the_background_are_refused(ramp, tmp_path, colours):
    """--invert draws white dots; with --background white every pixel of the picture was white (a held-out
    review)."""
    result = CliRunner().invoke(main, ["torus", str(ramp), "-M", 50, *colours, "-o", str(tmp_path / "a.png")])
    assert result.exit_code == 1 and "the same colour: nothing would show" in result.output
    assert not (tmp_path / "a.png").exists()


def test_a_pen_too_wide_for_the_page_is_refused():
    """The inset stops at a quarter of the shorter side: a 500 mm pen on a 300-unit page drew a stroke 750 units
    wide, and one dot of a 50 mm pen inked 0.6 mm past a 100 mm page (a held-out review)."""
    centres = np.array([[10.0, 10.0], [30.0, 20.0]])
    with pytest.raises(StippleError, match="the pen is too wide for the page"):
        flat_dots([("dots", "black", centres)], (40.0, 30.0), tone_radius=0.2, pen=12.6, dot_style="point")
    (dots,) = flat_dots([("dots", "black", centres)], (40.0, 30.0), tone_radius=0.2, pen=12.4, dot_style="point")
    assert len(dots.centres) >= 1  # just under the limit: drawn (the two dots are thinned to one for that pen)


def test_a_pen_too_wide_for_the_map_is_refused_as_on_a_flat_page():
    """The map's inset stops at a quarter of its height as a flat page's does; a 45 mm pen on a 100 mm map inked
    past its edges without a word (the flat page's refusal had no twin here)."""
    with pytest.raises(StippleError, match="the pen is too wide for the page"):
        pen_sphere_drawing(30, "equirect", "point", 45.0)
