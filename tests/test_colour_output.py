"""``stipple colour`` and the pen paths for plotters: layers per ink, counts by largest remainder, ink
coverage of the filled dot style, and the vpype plug-in (skipped when vpype is not installed)."""

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main
from stipple.colour import separate
from stipple.multiclass import class_counts
from stipple.render.pen import SEGMENTS_PER_TURN, dot_paths


@pytest.fixture
def colour_image(tmp_path):
    """Left half red (magenta, yellow and a little black), right half a grey teal (cyan and black): four inks."""
    pixels = np.zeros((12, 16, 3), dtype=np.uint8)
    pixels[:, :8] = (230, 40, 40)
    pixels[:, 8:] = (40, 110, 110)
    path = tmp_path / "flag.png"
    Image.fromarray(pixels).save(path)
    return path, pixels / 255.0


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_colour_writes_one_layer_per_ink_with_counts_by_mass(colour_image, tmp_path):
    path, rgb = colour_image
    outputs = [tmp_path / name for name in ("dots.csv", "dots.svg", "dots.png")]
    args = ["colour", path, "-M", 300, "--iterations", 15, "-q"]
    result = run(args + [item for output in outputs for item in ("-o", output)])
    assert result.exit_code == 0, result.output
    rows = [line.split(",") for line in outputs[0].read_text().splitlines()]
    assert rows[0] == ["x", "y", "layer"] and len(rows) == 301
    layers = separate(rgb, "cmyk")
    expected = class_counts([layer.density.sum() for layer in layers], 300)
    found = [sum(row[2] == layer.name for row in rows[1:]) for layer in layers]
    assert found == expected.tolist() and min(found) > 0
    # Magenta and yellow dots lie on the red half, cyan on the blue-grey half.
    x = {layer.name: np.array([float(row[0]) for row in rows[1:] if row[2] == layer.name]) for layer in layers}
    assert np.all(x["magenta"] < 8) and np.all(x["yellow"] < 8) and np.mean(x["cyan"] >= 8) > 0.9
    svg = outputs[1].read_text()
    assert svg.count('inkscape:groupmode="layer"') == 4 and svg.count("<circle") - svg.count('class="copy"') == 300
    assert 'fill="#ff00ff"' in svg and 'inkscape:label="4-black"' in svg
    picture = np.asarray(Image.open(outputs[2]).convert("RGB"), dtype=float)
    left, right = picture[:, : picture.shape[1] // 2], picture[:, picture.shape[1] // 2 :]
    assert left[..., 0].mean() > left[..., 1].mean() + 40  # red on the left
    assert right[..., 2].mean() > right[..., 0].mean() + 20  # teal on the right


@pytest.mark.parametrize("style", [[], ["--dot-style", "filled", "--pen-width", "0.2mm", "--order"]])
def test_an_ink_without_dots_leaves_its_layer_number_free_and_is_named(tmp_path, style):
    """A held-out review: on a photo whose cyan got no dots, magenta became layer 1 of the SVG (and of vpype), so
    every pen after it moved a slot, and nothing said cyan was empty. A red and white image has no cyan and no
    black: magenta and yellow keep layers 2 and 3."""
    red_and_white(tmp_path / "red.png")
    args = ["colour", tmp_path / "red.png", "-M", 60, "--iterations", 2, *style, "-o", tmp_path / "dots.svg"]
    result = run(args)
    assert result.exit_code == 0, result.output
    assert "stipple: note: no dots for cyan, black" in result.stderr, result.stderr
    if "--order" in style:  # each ink's pen-up travel says whose it is
        assert "pen-up travel (magenta)" in result.stderr and "pen-up travel (yellow)" in result.stderr
    svg = (tmp_path / "dots.svg").read_text()
    labels = svg.split('inkscape:label="')[1:]
    assert [label.split('"')[0] for label in labels] == ["2-magenta", "3-yellow"]
    assert 'id="layer2"' in svg and 'id="layer3"' in svg and 'id="layer1"' not in svg
    assert "no dots" not in run([*args[:-2], "-q", "-o", tmp_path / "quiet.svg"]).stderr


def test_colour_refuses_gray_only_options(colour_image):
    """``stipple colour`` does not offer them; ``stipple torus --palette``, which does, refuses them."""
    result = run(["colour", colour_image[0], "-M", 50, "--invert", "-q"])
    assert result.exit_code == 2 and "No such option '--invert'" in result.output
    result = run(["torus", colour_image[0], "--palette", "cmyk", "-M", 50, "--invert", "-q"])
    assert result.exit_code == 1 and "not colour separation" in result.output


def test_filled_dots_ink_the_whole_disc_and_stay_inside():
    radius, pen = 1.0, 0.13
    (path,) = dot_paths(np.array([[3.0, 4.0]]), radius, "filled", pen)
    centre = 3 + 4j
    assert np.abs(path - centre).max() <= radius - pen / 2 + 1e-12
    starts, ends = path[:-1], path[1:]
    grid = np.linspace(-radius, radius, 81)
    probes = centre + (grid[:, None] + 1j * grid[None, :]).ravel()
    probes = probes[np.abs(probes - centre) <= radius - 1e-9]
    # Distance from each probe to the polyline: the pen (half width pen/2) must reach every point of the disc.
    along = np.clip(((probes[:, None] - starts) * np.conj(ends - starts)).real / np.abs(ends - starts) ** 2, 0, 1)
    distance = np.abs(probes[:, None] - (starts + along * (ends - starts))).min(axis=1)
    sagitta = (radius - pen / 2) * (1 - np.cos(np.pi / SEGMENTS_PER_TURN))  # the polygon's chord error
    assert distance.max() <= pen / 2 + sagitta + 1e-12
    (circle,) = dot_paths(np.array([[0.0, 0.0]]), radius, "circle", pen)
    np.testing.assert_allclose(np.abs(circle), radius - pen / 2)
    (point,) = dot_paths(np.array([[0.0, 0.0]]), radius, "point", pen)
    assert np.abs(point[1] - point[0]) == pytest.approx(pen / 10)


def test_vpype_plugin_adds_one_named_coloured_layer_per_ink(colour_image):
    vpype = pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import vpype_cli

    document = vpype_cli.execute(
        f"stipple -M 200 --separation cmyk --iterations 10 --dot-style filled --width 160mm --pen-width 0.5mm "
        f"{colour_image[0]}"
    )
    layers = document.layers
    assert len(layers) == 4
    names = [layer.property(vpype.METADATA_FIELD_NAME) for layer in layers.values()]
    assert names == ["cyan", "magenta", "yellow", "black"]
    assert sum(len(layer) for layer in layers.values()) == 200
    pen = vpype.convert_length("0.5mm")
    assert all(layer.property(vpype.METADATA_FIELD_PEN_WIDTH) == pytest.approx(pen) for layer in layers.values())
    assert layers[2].property(vpype.METADATA_FIELD_COLOR) == vpype.Color(255, 0, 255)
    width = vpype.convert_length("160mm")
    assert document.page_size == pytest.approx((width, width * 12 / 16))
    centres = np.array([path.mean() for layer in layers.values() for path in layer])
    assert np.all((centres.real >= 0) & (centres.real <= width) & (centres.imag >= 0) & (centres.imag <= width * 0.75))


def test_vpype_plugin_keeps_an_inks_layer_number_where_an_earlier_ink_has_no_dots(tmp_path):
    """A red and white image has no cyan: magenta is layer 2 and yellow layer 3, as in stipple colour's SVG (the
    plugin made them 1 and 2, and every pen after the empty ink moved a slot)."""
    vpype = pytest.importorskip("vpype", reason="vpype is not installed (pip install 'stipple[plotter]')")
    import vpype_cli

    red_and_white(tmp_path / "red.png")
    document = vpype_cli.execute(
        f"stipple -M 60 --separation cmyk --iterations 2 --dot-style filled --width 80mm --pen-width 0.3mm "
        f"{tmp_path / 'red.png'}"
    )
    names = {number: layer.property(vpype.METADATA_FIELD_NAME) for number, layer in document.layers.items()}
    assert names == {2: "magenta", 3: "yellow"}


def red_and_white(path):
    """A 16 x 12 image, red on the left and white on the right: magenta and yellow ink, no cyan, no black."""
    pixels = np.full((12, 16, 3), 255, dtype=np.uint8)
    pixels[:, :8] = (255, 0, 0)
    Image.fromarray(pixels).save(path)


def composite_svg(svg, shape, per_pixel=8):
    """The SVG's circles as a viewer composites them on white paper, sampled ``per_pixel``² times a user unit:
    each layer's union of discs, laid over what is below, or multiplied with it where the layer's style says
    ``mix-blend-mode:multiply``. Returns ``(rows, columns, 3)`` colours in [0, 1]."""
    import re

    rows, columns = shape
    y, x = (np.mgrid[0 : rows * per_pixel, 0 : columns * per_pixel] + 0.5) / per_pixel
    colour = np.ones((*x.shape, 3))
    for head, body in re.findall(r"(<g [^>]*>)(.*?)</g>", svg, flags=re.S):
        ink = np.array([int(re.search(r'fill="#(\w{6})"', head).group(1)[i : i + 2], 16) for i in (0, 2, 4)]) / 255
        covered = np.zeros(x.shape, dtype=bool)
        for cx, cy, r in re.findall(r'<circle cx="([-\d.]+)" cy="([-\d.]+)" r="([-\d.]+)"', body):
            covered |= (x - float(cx)) ** 2 + (y - float(cy)) ** 2 < float(r) ** 2
        painted = colour * ink if "mix-blend-mode:multiply" in head else np.broadcast_to(ink, colour.shape)
        colour = np.where(covered[..., None], painted, colour)
    return colour.reshape(rows, per_pixel, columns, per_pixel, 3).mean(axis=(1, 3))


def test_the_svg_composites_its_inks_as_the_png_prints_them(colour_image, tmp_path):
    """Tone-style dots of different inks overlap; the PNG multiplies them. An SVG whose layers were painted over
    each other showed the last ink where they overlap (a red drawn orange-yellow)."""
    path, rgb = colour_image
    svg, png = tmp_path / "dots.svg", tmp_path / "dots.png"
    result = run(["colour", path, "-M", 300, "--iterations", 15, "-q", "-o", svg, "-o", png, "--png-width", 160])
    assert result.exit_code == 0, result.output
    seen = composite_svg(svg.read_text(), rgb.shape[:2])
    printed = np.asarray(Image.open(png).convert("RGB"), dtype=float) / 255
    for half in (np.s_[:, 1:7], np.s_[:, 9:15]):
        big = (half[0], slice(half[1].start * 10, half[1].stop * 10))
        assert np.abs(seen[half].mean(axis=(0, 1)) - printed[big].mean(axis=(0, 1))).max() < 0.03


def test_the_svg_is_as_dark_as_the_png_along_the_edges(tmp_path):
    """The tone style's page wraps around: the PNG draws a disc crossing an edge across the opposite one too, and
    the radii count on it. The SVG had one circle per dot: a light frame (a dark page's outermost unit 0.64 dark
    in the SVG, 0.80 in the PNG and inside)."""
    path, svg, png = tmp_path / "dark.png", tmp_path / "t.svg", tmp_path / "t.png"
    Image.fromarray(np.full((32, 48), 50, dtype=np.uint8)).save(path)
    result = run(["torus", path, "-M", 1500, "--iterations", 30, "-q", "-o", svg, "-o", png, "--png-width", 480])
    assert result.exit_code == 0, result.output
    seen = 1 - composite_svg(svg.read_text(), (32, 48)).mean(axis=2)
    printed = 1 - np.asarray(Image.open(png).convert("L"), dtype=float).reshape(32, 10, 48, 10).mean(axis=(1, 3)) / 255
    ring = np.ones((32, 48), dtype=bool)
    ring[1:-1, 1:-1] = False
    assert abs(seen[ring].mean() - printed[ring].mean()) < 0.03, (seen[ring].mean(), printed[ring].mean())
    assert abs(seen[ring].mean() - seen[~ring].mean()) < 0.05


def test_the_gray_palette_prints_the_image_luminance(tmp_path):
    """One black ink prints gray: its tone must be the image's luminance, not the mean of its channels (a
    saturated blue, luminance 0.21, was drawn 0.34)."""
    pixels = np.zeros((16, 24, 3), dtype=np.uint8)
    pixels[:, :12] = (20, 40, 200)  # blue: luminance 0.21, channel mean 0.34
    pixels[:, 12:] = (230, 210, 20)  # yellow: luminance 0.76, channel mean 0.60
    path, png = tmp_path / "blocks.png", tmp_path / "gray.png"
    Image.fromarray(pixels).save(path)
    result = run(["colour", path, "-M", 1200, "--palette", "gray", "--iterations", 30, "-q", "-o", png])
    assert result.exit_code == 0, result.output
    drawn = np.asarray(Image.open(png).convert("RGB"), dtype=float) / 255 @ [0.299, 0.587, 0.114]
    luminance = pixels / 255 @ [0.299, 0.587, 0.114]
    columns = drawn.shape[1]
    for drawn_half, wanted in (
        (drawn[:, 3 * columns // 24 : 9 * columns // 24], luminance[0, 0]),
        (drawn[:, 15 * columns // 24 : 21 * columns // 24], luminance[0, -1]),
    ):
        assert abs(drawn_half.mean() - wanted) < 0.03, (drawn_half.mean(), wanted)
