"""``-M auto``: the pen dot's ink against the drawn preview, the count on constant images by hand, the cap, and
the command line's messages and metadata."""

import warnings

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main
from stipple.io.png import render_picture
from stipple.render.dots import Dots
from stipple.render.pen import dot_paths
from stipple.render.pen_count import AUTO_SHARE, auto_count, pen_density, pen_dot, reachable_tone


@pytest.mark.parametrize("style", ["point", "filled", "circle"])
def test_pen_dot_area_is_what_the_preview_inks(style):
    pen = 10.0
    area, reach = pen_dot(style, pen)
    dots = Dots("d", (0.0, 0.0, 0.0), np.array([[50.0, 50.0]]), np.array([reach]))
    dots.paths = dot_paths(dots.centres, dots.radii, style, pen)
    picture = np.asarray(render_picture([dots], (100, 100), 400, pen_width=pen), dtype=np.float64)
    inked = (1 - picture / 255).sum() / 16  # 4 pixels per user unit
    assert inked == pytest.approx(area, rel=0.015)


def test_count_carries_the_ink_of_a_constant_image():
    darkness = np.full((30, 60), 0.3)
    count = auto_count(darkness, 120.0, "point", 0.4)  # paper 120 x 60 mm
    area = (np.pi / 4 + 0.1) * 0.16
    assert count.paper_area == pytest.approx(7200.0)
    assert count.ink_area == pytest.approx(0.3 * 7200.0)
    assert count.n_points == count.tone_points == round(0.3 * 7200 / area)
    assert not count.capped and count.note() is None
    assert "ink" in count.reason() and str(count.n_points) in count.reason()


def test_count_scales_with_the_pen_and_the_paper():
    darkness = np.full((20, 20), 0.25)
    base = auto_count(darkness, 50.0, "filled", 0.3).n_points
    assert auto_count(darkness, 100.0, "filled", 0.3).n_points == pytest.approx(4 * base, rel=1e-3)
    assert auto_count(darkness, 50.0, "filled", 0.6).n_points == pytest.approx(base / 4, rel=1e-2)


@pytest.mark.parametrize("style", ["point", "filled"])
def test_dark_image_gets_the_largest_packing_and_a_note(style):
    darkness = np.full((10, 10), 0.95)
    count = auto_count(darkness, 20.0, style, 0.8)
    area, reach = pen_dot(style, 0.8)
    hexagonal_sites = 400 * 2 / (np.sqrt(3) * (reach / 0.45) ** 2)  # dots of reach r, 0.45 d apart, on 400 mm²
    # the ink of the reachable tone; at most the lattice's sites at the spacing that leaves 95 % of an optimised
    # stipple's nearest neighbours apart
    carried = int(round(reachable_tone(style) * 400 / area))
    assert count.capped and count.carried_points == carried
    assert count.n_points == int(round(AUTO_SHARE[style] * carried))  # filled: room for the closest dots
    assert count.n_points <= count.packing_points == int(np.floor(hexagonal_sites * 0.82**2))
    assert count.n_points < count.tone_points
    assert "lighter" in count.note() and "without touching" in count.reason()


@pytest.mark.parametrize(
    "darkness, style, message",
    [(np.zeros((4, 4)), "point", "less than one pen dot"), (np.ones((4, 4)), "disc", "pen dot style")],
)
def test_refusals(darkness, style, message):
    with pytest.raises(Exception, match=message):
        auto_count(darkness, 10.0, style, 0.3)


def flat_gray(tmp_path, darkness, size=48):
    path = tmp_path / "gray.png"
    Image.fromarray(np.full((size, size), round(255 * (1 - darkness)), np.uint8)).save(path)
    return path


def test_auto_on_the_command_line(tmp_path):
    image = flat_gray(tmp_path, 0.3)
    svg, png = tmp_path / "out.svg", tmp_path / "out.png"
    arguments = ["torus", str(image), "-M", "auto", "--dot-style", "point", "--pen-width", "0.5mm", "--width", "24mm"]
    result = CliRunner().invoke(main, [*arguments, "-o", str(svg), "-o", str(png), "--png-width", "768", "-v"])
    assert result.exit_code == 0, result.output
    expected = auto_count(np.full((48, 48), 1 - round(255 * 0.7) / 255), 24.0, "point", 0.5)
    assert f"-M auto: {expected.n_points} dots" in result.output and "packing count" in result.output
    text = svg.read_text()
    assert text.count("<path") == expected.n_points and f"-M auto: {expected.n_points} dots" in text
    drawn = 1 - np.asarray(Image.open(png), dtype=np.float64) / 255
    assert drawn[96:-96, 96:-96].mean() == pytest.approx(0.3, abs=0.04)  # the pen dots carry the tone


@pytest.mark.parametrize(
    "style, noted",
    [
        (["--dot-style", "filled"], True),
        (["--style", "plotter"], True),
        ([], False),
        (["--style", "plotter", "--dot-radius", "3mm"], False),  # a fixed radius: dots may touch and overlap
    ],
)
def test_a_given_count_in_the_plotter_style_says_which_tones_it_cannot_reach(tmp_path, style, noted):
    """-M auto says that tones darker than the no-touch packing's come out lighter; a given -M did not (a dark
    photo drawn with filled pen dots: its darkest tenth 0.44 for 0.9, silently)."""
    image = flat_gray(tmp_path, 0.8)
    arguments = ["torus", str(image), "-M", "200", "--iterations", "3", *style, "-o", str(tmp_path / "out.svg")]
    result = CliRunner().invoke(main, arguments)
    assert result.exit_code == 0, result.output
    line = f"tones darker than {reachable_tone('filled'):.0%} will be lighter"
    assert (line in result.output) == noted, result.output


def test_under_invert_the_note_names_the_light_tones(tmp_path):
    """With --invert the dots are light on a dark ground: the image's lightest tones are the ones the plotter
    style cannot reach, and they come out darker (the note said darker tones would be lighter)."""
    image = flat_gray(tmp_path, 0.1)  # a dark page: under --invert, light dots' ink is its lightness, 0.9
    arguments = ["torus", str(image), "-M", "200", "--iterations", "3", "--invert", "--style", "plotter"]
    result = CliRunner().invoke(main, [*arguments, "-o", str(tmp_path / "out.svg")])
    assert result.exit_code == 0, result.output
    assert f"tones lighter than {reachable_tone('filled'):.0%} will be darker" in result.output, result.output
    assert "lightest 1 % is 90% light" in result.output
    # -M auto's own lines alike (they still named the dark tones: a code review)
    auto = ["torus", str(image), "-M", "auto", "--iterations", "2", "--invert", "--dot-style", "filled"]
    result = CliRunner().invoke(main, [*auto, "-o", str(tmp_path / "auto.svg")])
    assert result.exit_code == 0, result.output
    assert "lighter ones drawn at" in result.output and "lightest 1 % is 90% light" in result.output, result.output


def test_too_few_point_dots_for_the_ink_get_a_note_with_the_count_that_carries_it(tmp_path):
    """A point pen's dot inks a fixed area: -M 200 of a 0.5 mm pen on a 0.4 gray page drew it about a seventh as
    dark, with only the note about the darkest tones (the page has none)."""
    image = flat_gray(tmp_path, 0.4)
    arguments = [
        "torus",
        str(image),
        "--iterations",
        "3",
        "--dot-style",
        "point",
        "--pen-width",
        "0.5mm",
        "--width",
        "20mm",
    ]
    few = CliRunner().invoke(main, [*arguments, "-M", "200", "-o", str(tmp_path / "few.svg")])
    assert few.exit_code == 0 and "point dots of a 0.5 mm pen ink" in few.output, few.output
    tone = int(few.output.split("carry its ink, ")[1].split(")")[0])
    assert tone == pytest.approx(0.4 * 20 * 20 / ((np.pi / 4 + 0.1) * 0.25), rel=0.01)  # a 20 mm square page
    # The count -M auto makes of the same page (it named the ink of tones the pen cannot reach: a dark image's
    # note said 10763 where -M auto drew 6792).
    auto = CliRunner().invoke(main, [*arguments, "-M", "auto", "-o", str(tmp_path / "auto.svg")])
    assert f"-M auto: {tone} dots" in auto.output, auto.output
    enough = CliRunner().invoke(main, [*arguments, "-M", str(tone), "-o", str(tmp_path / "enough.svg")])
    assert enough.exit_code == 0 and "point dots" not in enough.output
    # More than fit without touching: the drawing leaves dots out (a colour run of 20000 left out 8044), and says so.
    packing = int(np.floor(reachable_tone("point") * 400 / ((np.pi / 4 + 0.1) * 0.25)))
    many = CliRunner().invoke(main, [*arguments, "-M", str(packing + 50), "-o", str(tmp_path / "many.svg")])
    assert many.exit_code == 0 and f"more than the {packing} that fit" in many.output, many.output
    assert "left out" in (tmp_path / "many.svg").read_text()


@pytest.mark.parametrize(
    "style, says",
    [
        ("filled", "flatter and lighter"),
        ("circle", "flatter and lighter"),
        ("point", "its lighter tones come out darker"),
    ],
)
def test_more_pen_dots_than_carry_the_ink_get_a_note_with_that_count(tmp_path, style, says):
    """A held-out review: -M 8000 filled dots of a 1 mm pen, where 6744 carry the ink the pen reaches (-M auto
    takes 0.85 of them), drew a portrait a flat light gray (luminance RMSE 0.27 at 4 px against 0.08), and -M 4500 point
    dots against 4081 drew its light tones darker, with no note. Now a count above the dots that carry the ink says
    so and names it; that count itself, and -M auto's, do not."""
    image = flat_gray(tmp_path, 0.3)
    arguments = ["torus", str(image), "--iterations", "2", "--dot-style", style, "--width", "20mm"]
    arguments += ["--pen-width", "0.5mm"]
    darkness = 1 - np.asarray(Image.open(image), dtype=np.float64) / 255
    count = auto_count(darkness, 20.0, style, 0.5)
    assert count.n_points == round(AUTO_SHARE[style] * count.carried_points)
    for given, noted in ((count.n_points, False), (count.carried_points, False), (count.carried_points + 5, True)):
        result = CliRunner().invoke(main, [*arguments, "-M", str(given), "-o", str(tmp_path / "given.svg")])
        assert result.exit_code == 0, result.output
        assert (f"more than the {count.carried_points} that carry the image's ink" in result.output) == noted
        assert (says in result.output) == noted, result.output


def test_colour_in_the_plotter_style_says_which_tones_it_cannot_reach(tmp_path):
    """As stipple torus: a colour drawing's inks together darker than the no-touch packing reaches got no note."""
    path = tmp_path / "dark.png"
    Image.fromarray(np.full((12, 16, 3), (20, 30, 90), dtype=np.uint8)).save(path)
    arguments = [
        "colour",
        str(path),
        "-M",
        "300",
        "--iterations",
        "3",
        "--style",
        "plotter",
        "-o",
        str(tmp_path / "c.svg"),
    ]
    result = CliRunner().invoke(main, arguments)
    assert result.exit_code == 0 and f"tones darker than {reachable_tone('filled'):.0%}" in result.output, result.output


@pytest.mark.parametrize(
    "extra, message",
    [
        ([], "pen dot style"),
        (["--dot-style", "point", "--palette", "cmyk"], "one ink"),
        (["--dot-style", "point", "-M", "many"], "'many' is not a whole number in decimal digits or 'auto'"),
    ],
)
def test_auto_refusals_on_the_command_line(tmp_path, extra, message):
    image = flat_gray(tmp_path, 0.3, size=16)
    result = CliRunner().invoke(main, ["torus", str(image), "-M", "auto", *extra, "-o", str(tmp_path / "o.svg")])
    assert result.exit_code != 0 and message in result.output and "Traceback" not in result.output
    assert not (tmp_path / "o.svg").exists()


def test_vpype_plugin_auto_count(tmp_path):
    pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import vpype_cli

    image = flat_gray(tmp_path, 0.3, size=32)
    document = vpype_cli.execute(
        f"stipple -M auto --dot-style point --pen-width 0.5mm --width 20mm --iterations 5 --order path {image}"
    )
    expected = auto_count(np.full((32, 32), 1 - round(255 * 0.7) / 255), 20.0, "point", 0.5).n_points
    drawn = sum(len(layer) for layer in document.layers.values())
    assert 0.9 * expected <= drawn <= expected  # five iterations leave a few dots too close for the pen: left out
    centres = np.array([line[0] for layer in document.layers.values() for line in layer])
    nearest = np.min(np.abs(centres[:, None] - centres[None, :]) + np.eye(len(centres)) * 1e9, axis=1)
    pen = 0.5 / 25.4 * 96
    assert nearest.min() >= 0.5 * pen / 0.45 * (1 - 1e-9)  # no two point dots (reach: half the pen) touch
    with pytest.raises(Exception, match="whole number or 'auto'"):
        vpype_cli.execute(f"stipple -M lots {image}")


@pytest.mark.parametrize(
    "options, message",
    [
        ("-w 0", "--width must be a length from 0.001mm to 1e\\+06mm"),
        ("--pen-width -1mm", "--pen-width must be a length from"),
        ("-M auto --dot-style point --pen-width 0", "--pen-width must be a length from"),
        ("--dot-radius -1mm", "--dot-radius must be a length from"),
        # A hostile sweep: tracebacks for a pen of 1e300 mm or 1e-300 mm, a page 1e299 cm wide with exit 0.
        ("--pen-width 1e300mm", "--pen-width must be a length from"),
        ("-M auto --dot-style point --pen-width 1e-300mm", "--pen-width must be a length from"),
        ("-w 1e300mm", "--width must be a length from"),
        ("--dot-radius 1e300", "--dot-radius must be a length from"),
        ("-M 3_00", "whole number or 'auto'"),
        ("--seed -1", "--seed must be an integer"),
        ("--palette cmy --black 0.5", "--black is for --palette cmyk"),
        ("-M 0", "number of points must be an integer in"),  # after a numpy divide-by-zero warning
    ],
)
def test_vpype_plugin_refuses_bad_options_in_one_line(tmp_path, options, message):
    """The plug-in drew stroke-width="-3.78" for --pen-width -1mm and raised ZeroDivisionError for a 0 pen."""
    pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import click
    import vpype_cli

    image = flat_gray(tmp_path, 0.3, size=16)
    with warnings.catch_warnings(), pytest.raises(click.ClickException, match=message):
        warnings.simplefilter("error", RuntimeWarning)  # one line: no numpy warning before it
        vpype_cli.execute(f"stipple -M 40 --iterations 2 {options} {image}")


@pytest.mark.parametrize("radius", [0.3, 0.5, 0.8, 1.2, 3.0])
@pytest.mark.parametrize("blend", ["over", "multiply"])
def test_a_png_disc_inks_its_area_at_any_size(radius, blend, rng):
    """Apart discs of a given radius (in output pixels) at random positions ink their area in all: the oracle
    is n pi r^2, the blurred comparisons of the drawn picture need it (Pillow's ellipse inked 0.89 of it at
    0.8 px and 1.13 at 0.3 px, so tone-true pictures came out light)."""
    step = 4 * radius + 3
    grid = np.arange(step / 2, 200 - step / 2, step)
    centres = np.stack(np.meshgrid(grid, grid), -1).reshape(-1, 2) + rng.uniform(-0.5, 0.5, (len(grid) ** 2, 2))
    dots = Dots("d", (0.0, 0.0, 0.0), centres, np.full(len(centres), radius))
    underlay = None if blend == "over" else (lambda *_: None)  # the direct canvas, or the masks' planes
    picture = render_picture([dots], (200, 200), 200, blend=blend, underlay=underlay)
    ink = (1 - np.asarray(picture, dtype=np.float64) / 255).sum()
    assert ink / (len(centres) * np.pi * radius**2) == pytest.approx(1.0, abs=0.015)


@pytest.mark.parametrize("colours", [[(0.0,) * 3, (0.5,) * 3], [(0.1, 0.2, 0.9), (1.0, 0.4, 0.0)]])
def test_opaque_layers_drawn_directly_equal_the_composited_masks(colours, rng):
    """Opaque inks "over" one another (discs, ellipses and pen paths overlapping, gray and colour) are drawn
    straight onto the canvas: the same bits as painting each layer's coverage mask over the planes (the path an
    underlay takes; an empty underlay changes nothing)."""
    centres = rng.random((2, 60, 2)) * 100
    first = Dots("a", colours[0], centres[0], rng.uniform(0.5, 6, 60))
    second = Dots("b", colours[1], centres[1], rng.uniform(0.5, 6, 60), squash=rng.uniform(0.3, 1, 60))
    second.angle = rng.uniform(0, np.pi, 60)
    third = Dots("c", colours[1], centres[1][:20], np.full(20, 2.0))
    third.paths = dot_paths(third.centres, third.radii, "circle", 0.8)
    layers = [first, second, third]
    direct = np.asarray(render_picture(layers, (100, 80), 300, pen_width=0.8))
    masks = np.asarray(render_picture(layers, (100, 80), 300, pen_width=0.8, underlay=lambda draw, scale: None))
    np.testing.assert_array_equal(direct, masks)
    assert len(np.unique(direct)) > 3


def test_pen_density_clips_only_where_the_dots_would_pack_too_close():
    """The density the pen's dots are placed by: its densest part over its mean at most what the no-touch packing
    allows, unchanged below the clip and where nothing is that dense; a constant density is never clipped."""
    rng = np.random.default_rng(5)
    darkness = np.clip(rng.random((40, 60)) ** 3 * 1.5, 0, 1)
    area = pen_dot("point", 0.5)[0]
    paper = 60.0 * 60.0 * 40 / 60
    for n_points in (200, 800, 2000):
        allowed = reachable_tone("point") * paper / (n_points * area)
        placed = pen_density(darkness, n_points, 60.0, "point", 0.5)
        if darkness.max() <= allowed * darkness.mean():
            assert placed is darkness
            continue
        level = placed.max()
        assert level / placed.mean() == pytest.approx(allowed, rel=1e-6)
        assert np.array_equal(placed[darkness < level], darkness[darkness < level])
    flat = np.full((10, 10), 0.9)  # far too many dots for the pen: clipped, but still the same (even) density
    assert np.ptp(pen_density(flat, 10**6, 10.0, "filled", 0.3)) == 0


def test_auto_count_in_the_darkest_tones_leaves_no_dot_out(tmp_path):
    """A dark image at -M auto with a point pen: the dots are placed by the density clipped at the pen's reach, so
    the drawing needs to leave none out (it left out hundreds, irregularly) and the darks come out at the reach."""
    rows, columns = np.mgrid[0:48, 0:72]
    image = tmp_path / "dark.png"
    Image.fromarray((255 * (0.05 + 0.6 * columns / 72)).astype(np.uint8)).save(image)
    options = ["-M", "auto", "--dot-style", "point", "--pen-width", "0.5mm", "--width", "40mm", "-q"]
    result = CliRunner().invoke(main, ["torus", str(image), *options, "-o", str(tmp_path / "d.svg")])
    assert result.exit_code == 0, result.output
    text = (tmp_path / "d.svg").read_text()
    assert "left out" not in text and "-M auto:" in text


def test_vpype_progressive_passes_survive_dots_left_out(tmp_path):
    """A small ink split into passes of one dot each: when the pen's thinning left out every dot of a pass, the
    progressive order got an empty pass and raised (argmin of an empty sequence)."""
    pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import vpype_cli

    from stipple.vpype_plugin import kept_passes

    assert kept_passes([1, 1, 2, 4], np.array([True, False, False, True, True, False, True, True])) == [1, 1, 3]
    rgb = np.full((32, 32, 3), 30, np.uint8)
    rgb[10:13, 10:13] = (20, 60, 60)
    Image.fromarray(rgb).save(tmp_path / "dark.png")
    document = vpype_cli.execute(
        "stipple -M 3000 --iterations 5 --palette cmyk --order progressive --dot-style point --pen-width 0.5mm "
        f"--width 40mm {tmp_path / 'dark.png'}"
    )
    assert 1000 < sum(len(layer) for layer in document.layers.values()) <= 3000


def test_colour_pen_dots_are_placed_by_the_clipped_density_too(tmp_path):
    """stipple colour with a pen left 218 dots out of a dark ramp's drawing and drew its darkest tenth lighter than
    the one before: now all the inks' dots are placed by their density together clipped at the pen's reach, as
    stipple torus's, and the drawing is the same as stipple torus's of the gray image."""
    image = tmp_path / "ramp.png"
    Image.fromarray(np.tile(np.linspace(250, 5, 72).astype(np.uint8), (48, 1))).save(image)
    pen = ["-M", "2000", "--dot-style", "point", "--pen-width", "0.5mm", "--width", "45mm", "-q"]
    colour = CliRunner().invoke(main, ["colour", str(image), "--palette", "gray", *pen, "-o", str(tmp_path / "c.svg")])
    assert colour.exit_code == 0, colour.output
    assert "left out" not in (tmp_path / "c.svg").read_text()
    from stipple.colour import placed_layers, separate
    from stipple.render.pen_count import pen_density

    rgb = np.asarray(Image.open(image).convert("RGB"), dtype=float) / 255
    (layer,) = placed_layers(separate(rgb, "gray"), lambda union: pen_density(union, 2000, 45.0, "point", 0.5))
    assert np.allclose(layer.density, pen_density(separate(rgb, "gray")[0].density, 2000, 45.0, "point", 0.5))
    assert layer.density.max() < separate(rgb, "gray")[0].density.max()  # clipped


@pytest.mark.parametrize("separation", ["gray", "cmy"])
def test_progressive_inks_are_placed_by_the_clipped_density(separation):
    """The plugin's --order progressive built its problems without the pen's clip (its darkest places relied on
    leaving dots out): the placement now reaches one ink's levels and several inks' joint problem alike."""
    from stipple.colour import separate
    from stipple.progressive import progressive_colour

    red, green = np.meshgrid(np.linspace(0.05, 0.95, 30), np.linspace(0.1, 0.9, 20))
    rgb = np.stack([red, green, np.full((20, 30), 0.4)], -1)
    layers, result, _ = progressive_colour(
        rgb, 400, separation=separation, placement=lambda union: np.minimum(union, 0.3), iterations=2, levels=2
    )
    union = sum(layer.density for layer in layers)
    original = sum(layer.density for layer in separate(rgb, separation))
    assert union.max() <= 0.3 + 1e-12 < original.max()
    assert np.allclose(union[original <= 0.3], original[original <= 0.3])
    assert len(result.points) == 400


def test_colour_pen_notes_speak_of_the_image_not_of_the_clipped_placement(tmp_path):
    """The pen's clip lowers the density the dots are placed by; the notes on the image's darkest tones must still
    give the image's own (a photo's darkest 1 %, 100 % dark, was reported as 71 %)."""
    from stipple.colour import separate, union_darkness

    image = tmp_path / "ramp.png"
    ramp = np.linspace(250, 5, 72).astype(np.uint8)
    Image.fromarray(np.dstack([np.tile(ramp, (48, 1))] * 3)).save(image)
    paper = 45.0 * 45.0 * 48 / 72
    packing = int(np.floor(reachable_tone("point") * paper / pen_dot("point", 0.5)[0]))
    options = ["-M", str(int(0.9 * packing)), "--dot-style", "point", "--pen-width", "0.5mm", "--width", "45mm"]
    result = CliRunner().invoke(main, ["colour", str(image), "--palette", "gray", *options, "--iterations", "2"])
    rgb = np.asarray(Image.open(image).convert("RGB"), dtype=float) / 255
    darkest = np.percentile(union_darkness(separate(rgb, "gray")), 99)
    assert result.exit_code == 0 and f"the image's darkest 1 % is {darkest:.0%} dark" in result.output, result.output


def test_dots_left_out_are_said_on_stderr_unless_quiet(tmp_path):
    """Only the SVG's comment counted the dots a filled-dot drawing left out (2171 of 6000 on a dark image)."""
    rows, columns = np.mgrid[0:30, 0:45]
    image = tmp_path / "dark.png"
    Image.fromarray((255 * (0.05 + 0.3 * columns / 45)).astype(np.uint8)).save(image)
    base = ["torus", str(image), "-M", "2000", "--dot-style", "filled", "--pen-width", "0.5mm", "--width", "30mm"]
    base += ["--iterations", "20", "-o", str(tmp_path / "f.svg")]
    said = CliRunner().invoke(main, base)
    assert said.exit_code == 0, said.output
    (line,) = [line for line in said.output.splitlines() if "left out" in line]
    assert line.startswith("stipple: note: ") and "of 2000 dots left out" in line
    assert line.split("note: ")[1] in (tmp_path / "f.svg").read_text()
    quiet = CliRunner().invoke(main, [*base, "-q"])
    assert quiet.exit_code == 0 and "left out" not in quiet.output


def test_the_lighter_note_names_the_count_that_m_auto_makes_on_a_dark_page(tmp_path):
    """A page darker than the pen reaches: the note named the dots of all its ink (10763 on a dark photo), which
    -M auto then refused as more than fit (6792)."""
    image = flat_gray(tmp_path, 0.15)
    arguments = ["torus", str(image), "--iterations", "2", "--dot-style", "point", "--pen-width", "0.5mm"]
    arguments += ["--width", "20mm"]
    few = CliRunner().invoke(main, [*arguments, "-M", "100", "-o", str(tmp_path / "few.svg")])
    carried = int(few.output.split("carry its ink, ")[1].split(")")[0])
    auto = CliRunner().invoke(main, [*arguments, "-M", "auto", "-o", str(tmp_path / "auto.svg")])
    assert f"-M auto: {carried} dots" in auto.output, (few.output, auto.output)


def test_dot_radius_with_point_dots_is_refused(tmp_path):
    """A point dot's path does not depend on the radius, which only switched the no-touch rule off (277 pairs)."""
    image = flat_gray(tmp_path, 0.4)
    result = CliRunner().invoke(
        main,
        [
            "torus",
            str(image),
            "-M",
            "50",
            "--dot-style",
            "point",
            "--dot-radius",
            "0.01mm",
            "-o",
            str(tmp_path / "p.svg"),
        ],
    )
    assert result.exit_code == 1 and "--dot-radius does not size --dot-style point" in result.output


def test_vpype_plugin_says_how_many_dots_it_left_out(tmp_path, capsys):
    pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import vpype_cli

    image = flat_gray(tmp_path, 0.1, size=16)
    document = vpype_cli.execute(f"stipple -M 3000 --dot-style point --pen-width 0.5mm -w 20mm --iterations 3 {image}")
    drawn = sum(len(layer) for layer in document.layers.values())
    assert f"{3000 - drawn} of 3000 dots left out" in capsys.readouterr().err


def test_a_sphere_maps_pen_dots_are_placed_by_the_clipped_map(tmp_path):
    """The sphere's pen dots were placed by the unclipped map: the topography at M = 5000 with a 0.5 mm pen, 100 mm
    wide, left 556 dots out of the equirectangular map. Clipped as an image's darkness is, none."""
    from stipple.pipelines.pen import sphere_pen_density
    from stipple.render.dots import sphere_per_radian
    from stipple.sphere_density import CellMap

    rows, columns = np.mgrid[0:45, 0:90]
    peaks = 0.05 + np.exp(-(((rows - 15) ** 2 + (columns - 30) ** 2) / 30.0))
    density = CellMap(peaks)
    draw = {"dot_style": "circle", "dot_radius": None, "style": "plotter", "width": (100.0, "mm")}
    draw["pen_width"] = (0.5, "mm")
    clipped = sphere_pen_density(density, 1500, draw, "equirect")
    mean = np.average(clipped.values, weights=clipped.cell_areas)
    area = np.pi * 0.5**2
    allowed = reachable_tone("circle") * 4 * np.pi * sphere_per_radian("equirect", 100.0) ** 2 / (1500 * area)
    assert clipped.values.max() == pytest.approx(allowed * mean, rel=1e-6)
    low = peaks < clipped.values.max()
    assert np.array_equal(clipped.values[low], peaks[low])
    np.save(tmp_path / "peaks.npy", peaks)
    options = ["--dot-style", "circle", "--pen-width", "0.5mm", "--width", "100mm", "--projection", "equirect"]
    result = CliRunner().invoke(
        main,
        [
            "sphere",
            str(tmp_path / "peaks.npy"),
            "-M",
            "1500",
            "--iterations",
            "40",
            *options,
            "-o",
            str(tmp_path / "s.svg"),
        ],
    )
    assert result.exit_code == 0 and "left out" not in result.output, result.output
    assert (tmp_path / "s.svg").read_text().count("<path ") == 1500


@pytest.mark.parametrize("allowed", [20.0, 80 / 35])
def test_the_clip_level_is_found_however_many_decades_the_density_spans(allowed):
    """The level was searched by halving [0, max] 60 times, so a map whose clip lies below 1e-18 (a narrow
    Gaussian's near 1e-35) was left unclipped: its pen map left 1399 of 1500 dots out (a held-out review). Here
    the values span 80 decades evenly, so the ratio at ``10^-m`` is about ``80 / m``."""
    from stipple.render.pen_count import clipped_density

    darkness = 10.0 ** -np.linspace(0, 80, 4000).reshape(40, 100)
    level = clipped_density(darkness, allowed).max()
    assert level < 1.0 and level / np.mean(np.minimum(darkness, level)) == pytest.approx(allowed, rel=1e-9)
    assert (level < 1e-30) == (allowed < 3)


def test_auto_count_with_a_fixed_dot_radius_is_refused(tmp_path):
    """-M auto counts the pen's smallest dots; with --dot-radius 1mm every one was drawn 1 mm wide, 7884 pairs of
    them touching, the picture nearly black (a held-out review)."""
    image = flat_gray(tmp_path, 0.3, size=16)
    args = ["torus", str(image), "-M", "auto", "--dot-style", "filled", "--pen-width", "0.5mm", "--dot-radius", "1mm"]
    result = CliRunner().invoke(main, [*args, "-o", str(tmp_path / "a.svg")])
    assert result.exit_code == 1 and "-M auto counts the pen's smallest dots" in result.output
    assert not (tmp_path / "a.svg").exists()
