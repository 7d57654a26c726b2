"""PNG pictures: dots and lines drawn antialiased (4× supersampled, box-filtered), and the spectrum plot."""

import io

import numpy as np
from PIL import Image, ImageDraw

from .. import allocator
from ..errors import StippleError
from .raster import disc_mask
from .units import BLACK, WHITE

SUPERSAMPLE = 4
# The ink of the ring that marks the globe's edge under an orthographic PNG (``underlay``).
OUTLINE_INK = 0.3
MAX_CANVAS_SIDE = 1 << 20
# Discs are rasterised in bands of about this many fine pixels.
MASK_BAND_PIXELS = 1 << 22
PATHS_PER_GROUP = 10000


def png_canvas(size, pixels_wide):
    """Per-axis scales ``(sx, sy)`` (fine pixels per user unit) and ``(width, height)`` of the supersampled canvas
    for a PNG ``pixels_wide`` wide of ``size``.

    The PNG has ``pixels_wide × round(pixels_wide · height / width)`` whole pixels (at least one row: a canvas less
    than half a pixel high is stretched onto it; ``check_png_canvas`` refuses such PNGs, the measuring pictures of
    ``stipple.render.flat.tone_stroke`` draw them) and the canvas maps ``size`` onto exactly those, so otherwise
    ``sy`` differs from ``sx`` by at most half a pixel over the height. (Until 2026-11-26 one
    scale served both axes and the last row was part paper: a 480×160 image drawn 1024 wide filled 341.25 of its
    342 rows, and against its input, stretched onto the same frame, a dot 150 rows down sat 0.29 input pixels
    high: luminance RMSE at σ = 4 px 0.0033 instead of 0.0019 on a page of text.)
    """
    width, height = size
    pixels_high = max(int(round(pixels_wide * height / width)), 1)
    columns, rows = int(round(pixels_wide)) * SUPERSAMPLE, pixels_high * SUPERSAMPLE
    return (columns / width, rows / height), (columns, rows)


def check_png_canvas(size, pixels_wide, layers=2):
    """Refuse a PNG whose drawing canvas is too large for a side limit or for the memory available.

    ``layers`` counts the canvas-sized images alive at once (the canvas and a background).
    """
    _, (columns, rows) = png_canvas(size, pixels_wide)
    picture = f"a PNG {pixels_wide} pixels wide of a {size[0]:g}×{size[1]:g} canvas"
    if max(png_canvas(size, 1)[1][1], SUPERSAMPLE * size[0] / size[1]) > MAX_CANVAS_SIDE:  # no width would do
        raise StippleError(
            f"a {size[0]:g}×{size[1]:g} canvas is too narrow for any PNG (one side over "
            f"{MAX_CANVAS_SIDE // SUPERSAMPLE} pixels where the other is one): use SVG"
        )
    if max(columns, rows) > MAX_CANVAS_SIDE:
        raise StippleError(
            f"{picture} would be {columns // SUPERSAMPLE}×{rows // SUPERSAMPLE} pixels, more than "
            f"{MAX_CANVAS_SIDE // SUPERSAMPLE} per side: use a smaller --png-width, or SVG"
        )
    # As before the canvas was fitted to whole pixels: refused below 7/8 of a pixel high or wide.
    if min(columns, round(SUPERSAMPLE * pixels_wide * size[1] / size[0])) < SUPERSAMPLE:
        raise StippleError(f"{picture} would be less than one pixel high or wide: use a larger --png-width, or SVG")
    needed, available = columns * rows * layers * 1.1, allocator.available_memory()
    if needed > available:
        raise StippleError(
            f"{picture} needs about {needed / 2**30:.1f} GiB of memory to draw, more than the "
            f"{available / 2**30:.1f} GiB available: use a smaller --png-width, or SVG"
        )


def png_bytes(image):
    buffer = io.BytesIO()
    image.save(buffer, format="PNG", optimize=False)
    return buffer.getvalue()


# A default PNG's longer side is at most this many times its side for a square canvas: a tall image gets the
# width of a square one until it is TALLEST times taller (a 3 x 512 strip was drawn 1024 x 174763 pixels, 5.4 GB
# of memory, a file that Pillow's decompression-bomb guard then refuses to read).
TALLEST = 4


def default_png_width(count, canvas=(1.0, 1.0)):
    """Pixels across a PNG of ``count`` dots on ``canvas`` (``(width, height)``, any units): at least 1024 and 8
    per two dots across a square's side, the height at most ``TALLEST`` times that (a very tall canvas is drawn
    narrower, down to one pixel)."""
    side = int(max(1024, 8 * round(np.sqrt(count) / 2)))
    width, height = (float(value) for value in canvas)
    return max(1, min(side, int(TALLEST * side * width / height))) if height > 0 else side


def picture_channels(colours):
    """The channels of a picture in ``colours`` (RGB in [0, 1]): 1 where every one is a gray, else 3."""
    return 1 if all(len(set(colour)) == 1 for colour in colours) else 3


def float_picture_layers(channels=3):
    """Bytes a supersampled pixel takes while a picture is drawn through float coverage (``render_picture`` with
    the globe's outline or inks multiplied): per channel a float32 plane and its 8-bit band, and the layer's 8-bit
    mask, its float32 fraction and the blend's two float32 temporaries. A gray globe 8192 pixels wide peaked at
    16.9 GB (15.7 bytes a pixel), where its check had counted 2 and passed it on a 23 GB machine."""
    return 5 * channels + 13


def check_png_outputs(formats, canvas, png_width, count, layers=2):
    """Before a run: refuse PNG outputs whose canvas (user units ``(width, height)``) would not fit in memory
    (``layers`` as for ``check_png_canvas``)."""
    if ".png" in formats:
        check_png_canvas(canvas, png_width or default_png_width(count, canvas), layers)


def spectrum_plot(frequencies, power, anisotropy, size=(800, 600)):
    """PNG bytes of two stacked line plots: log10 radially averaged power and anisotropy (dB) by frequency."""
    width, height = size
    image = Image.new("L", size, 255)
    draw = ImageDraw.Draw(image)
    with np.errstate(divide="ignore"):
        log_power = np.log10(np.asarray(power, dtype=float))
    panels = [
        ("log10 radially averaged power", np.where(np.isfinite(log_power), log_power, np.nan)),
        ("anisotropy (dB)", np.asarray([np.nan if a is None else a for a in anisotropy], dtype=float)),
    ]
    x = np.asarray(frequencies, dtype=float)
    for index, (title, values) in enumerate(panels):
        top = 20 + index * height // 2
        box = (60, top + 20, width - 20, top + height // 2 - 40)
        draw.rectangle(box, outline=0)
        finite = values[np.isfinite(values)]
        low, high = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
        high = high if high > low else low + 1
        px = box[0] + (x - x.min()) / max(np.ptp(x), 1) * (box[2] - box[0])
        py = box[3] - (values - low) / (high - low) * (box[3] - box[1])
        keep = np.isfinite(py)
        draw.line(list(zip(px[keep], py[keep], strict=True)), fill=0, width=1)
        draw.text((box[0], top), f"{title}: {low:.3g} .. {high:.3g}", fill=0)
        draw.text((box[0], box[3] + 4), f"frequency {x.min():g} .. {x.max():g}", fill=0)
    return png_bytes(image)


def render_line(pixels, size, pixels_wide, pen_width, closed=True, colour=BLACK, background=WHITE):
    """An antialiased image of a polyline of ``pen_width`` (user units) in ``colour`` on ``background``
    (grayscale when both are grays).

    ``pixels`` are the vertices in user units of a canvas of ``size = (width, height)``; drawn at 4× and reduced.
    The stroke is the union of discs along the line (``stroke_centres``), as pen paths are drawn: Pillow's lines,
    their width rounded to a quarter pixel, made ``stipple line``'s tone-true stroke lay down 4-7 % too much ink
    (a held-out ramp: 0.524 for 0.500), the calibration of ``tone_stroke`` landing on one of the rounding's steps.
    """
    channels = 1 if len(set(colour)) == 1 and len(set(background)) == 1 else 3
    paper, ink = _pixel_value(background, channels), _pixel_value(colour, channels)
    scale, canvas_size = png_canvas(size, pixels_wide)
    canvas = Image.new("L" if channels == 1 else "RGB", canvas_size, paper)
    vertices = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    path = vertices[:, 0] + 1j * vertices[:, 1]
    if closed and len(path) > 1:
        path = np.append(path, path[:1])
    centres = stroke_centres([path], pen_width, least_spacing=0.5 / scale[0])
    canvas.paste(ink, mask=_disc_mask(centres, np.full(len(centres), pen_width / 2), scale, canvas.size))
    return canvas.reduce(SUPERSAMPLE)


def render_picture(layers, size, pixels_wide, *, background=WHITE, pen_width=None, blend="over", underlay=None):
    """An antialiased PNG picture (``PIL.Image``) of ``Dots`` layers, drawn at 4× and box-filtered.

    ``blend`` "over" paints each layer's colour over what is below (one ink on any background); "multiply"
    prints inks on paper (overlapping cyan and yellow make green). ``underlay(draw, scale)`` may draw on a
    coverage mask first (the globe's outline; ``scale`` is ``png_canvas``'s ``(sx, sy)``), which is painted 8 % of
    the way from the background to the first layer's colour. The picture is grayscale when every colour is a gray.
    """
    channels = picture_channels([tuple(background)] + [tuple(dots.colour) for dots in layers])
    direct = blend == "over" and underlay is None
    check_png_canvas(size, pixels_wide, 2 if direct else float_picture_layers(channels))
    scale, canvas_size = png_canvas(size, pixels_wide)
    if direct:
        # Opaque inks over one another: each fine pixel takes the last covering layer's colour, drawn directly.
        mode = "L" if channels == 1 else "RGB"
        canvas = Image.new(mode, canvas_size, _pixel_value(background, channels))
        for dots in layers:
            _draw_layer(canvas, dots, scale, pen_width, _pixel_value(dots.colour, channels))
        return canvas.reduce(SUPERSAMPLE)
    # One float32 plane per channel (a gray picture needs one): the supersampled canvas is 16 million pixels
    # for the default 1024-pixel PNG, and an (H, W, 3) float64 picture took most of the drawing time.
    planes = [np.full((canvas_size[1], canvas_size[0]), background[k], dtype=np.float32) for k in range(channels)]
    if underlay is not None and layers:
        mask = Image.new("L", canvas_size, 0)
        underlay(ImageDraw.Draw(mask), scale)
        _paint(planes, _fraction(mask, OUTLINE_INK), layers[0].colour, "over")
    for dots in layers:
        _paint(planes, _fraction(_coverage(dots, canvas_size, scale, pen_width)), dots.colour, blend)
    bands = [Image.fromarray(np.round(np.clip(plane, 0, 1) * 255).astype(np.uint8), "L") for plane in planes]
    image = bands[0] if channels == 1 else Image.merge("RGB", bands)
    return image.reduce(SUPERSAMPLE)


def _fraction(mask, scale=1.0):
    """A coverage mask (``PIL.Image`` "L") as float32 fractions in [0, ``scale``]."""
    return np.asarray(mask, dtype=np.float32) * np.float32(scale / 255.0)


def _paint(planes, coverage, colour, blend):
    """Lay one ink on the picture's planes in place: over what is below, or multiplied with it."""
    for k, plane in enumerate(planes):
        target = plane * np.float32(colour[k]) if blend == "multiply" else np.float32(colour[k])
        plane += coverage * (target - plane)


def _pixel_value(colour, channels):
    """An RGB colour in [0, 1] as Pillow's 8-bit pixel value (gray for one channel)."""
    values = tuple(int(np.round(np.clip(colour[k], 0, 1) * 255)) for k in range(channels))
    return values[0] if channels == 1 else values


def _coverage(dots, canvas_size, scale, pen_width):
    """A mask (``PIL.Image`` "L") of the ink of one layer of dots on the supersampled canvas."""
    mask = Image.new("L", canvas_size, 0)
    _draw_layer(mask, dots, scale, pen_width, 255)
    return mask


def _draw_layer(canvas, dots, scale, pen_width, fill):
    """Draw one layer of dots with ``fill`` on a supersampled canvas (``PIL.Image``).

    Round discs, and their copies across a wrapping page's edges, are inked where a fine pixel's centre lies
    inside one (``stipple.io.raster.disc_mask``): a disc's ink is its area on average at any size. Pillow's
    ``ellipse`` was off by -11 to +13 % for discs of 0.3-1.2 output pixels (the dots of a dense stipple at the
    default PNG width), which made tone-true pictures light. Pen paths are the union of such discs along them
    (``stroke_centres``): Pillow's lines, their width rounded to whole pixels and their caps a pixel short, drew
    a point pen's preview 3 % lighter than its SVG.
    """
    if dots.paths is not None:
        # A group of paths at a time: a pen circle is about a hundred discs.
        for start in range(0, len(dots.paths), PATHS_PER_GROUP):
            centres = stroke_centres(dots.paths[start : start + PATHS_PER_GROUP], pen_width, 0.5 / scale[0])
            radii = np.full(len(centres), pen_width / 2)
            canvas.paste(fill, mask=_disc_mask(centres, radii, scale, canvas.size))
    elif dots.squash is None:
        centres, radii = np.asarray(dots.centres, dtype=float).reshape(-1, 2), np.asarray(dots.radii, dtype=float)
        if dots.copies is not None:
            centres, radii = np.concatenate([centres, dots.copies[0]]), np.concatenate([radii, dots.copies[1]])
        canvas.paste(fill, mask=_disc_mask(centres, radii, scale, canvas.size))
    else:
        draw = ImageDraw.Draw(canvas)
        # Foreshortened dots are the globe's, whose canvas is square: sx = sy.
        for centre, radius, squash, angle in zip(
            dots.centres * scale, dots.radii * scale[0], dots.squash, dots.angle, strict=True
        ):
            draw.polygon(
                ellipse_polygon(centre - 0.5, max(radius, 0.5), max(squash, 0.5 / max(radius, 0.5)), angle), fill=fill
            )


def stroke_centres(paths, pen_width, least_spacing=0.0):
    """Centres of discs ``pen_width`` wide along each pen path (complex vertices), at most an eighth of the width
    apart, both ends included: their union is the path stroked with round caps and joins, as the SVG's, its
    width short by less than 0.5 % between two discs. At least ``least_spacing`` apart (half a fine pixel of the
    drawing): a 0.001 mm pen's line took 2.5 GB and 14 s for 300 vertices."""
    spacing = max(pen_width / 8, least_spacing)
    paths = [np.asarray(path, dtype=complex) for path in paths if len(path)]
    if not paths:
        return np.zeros((0, 2))
    starts = np.concatenate([path[:-1] if len(path) > 1 else path for path in paths])
    ends = np.concatenate([path[1:] if len(path) > 1 else path for path in paths])
    steps = np.maximum(np.ceil(np.abs(ends - starts) / spacing).astype(np.int64), 1)
    segment = np.repeat(np.arange(len(steps)), steps + 1)  # each disc's segment, steps + 1 discs per segment
    first = np.cumsum(steps + 1) - (steps + 1)  # each segment's first disc
    fraction = (np.arange(len(segment)) - first[segment]) / steps[segment]
    points = starts[segment] + fraction * (ends[segment] - starts[segment])
    return np.column_stack([points.real, points.imag])


def _disc_mask(centres, radii, scale, canvas_size):
    """``disc_mask`` of discs on the supersampled canvas, as a ``PIL.Image`` "L" (0 or 255), drawn in bands of
    rows (the scanline counts are 4 bytes a pixel); ``scale`` is ``(sx, sy)``."""
    columns, rows = canvas_size
    mask = np.zeros((rows, columns), dtype=np.uint8)
    band = max(1, MASK_BAND_PIXELS // columns)
    top, bottom = (centres[:, 1] - radii) * scale[1], (centres[:, 1] + radii) * scale[1]
    for start in range(0, rows, band):
        stop = min(rows, start + band)
        near = (bottom >= start - 1) & (top <= stop + 1)
        shifted = centres[near] - [0.0, start / scale[1]]
        mask[start:stop][disc_mask(shifted, radii[near], scale, (stop - start, columns))] = 255
    return Image.fromarray(mask, "L")


def ellipse_polygon(centre, radius, squash=1.0, angle=0.0, segments=24):
    """Vertices ``[(x, y), ...]`` of a dot's outline (an ellipse when ``squash < 1``)."""
    t = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    local = radius * (squash * np.cos(t) + 1j * np.sin(t)) * np.exp(1j * angle)
    z = complex(centre[0], centre[1]) + local
    return list(zip(z.real, z.imag, strict=True))
