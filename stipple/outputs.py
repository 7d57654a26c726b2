"""Writing dots: CSV, SVG, PNG and GeoJSON, all-or-nothing (every temporary file fsynced, then all renamed)."""

import contextlib
import io
import json
import os
import re
import signal
import sys
import tempfile

import numpy as np
from PIL import Image, ImageDraw

from .drawing import Dots, angular_distances, capped_radii, ellipse_polygon, flat_dots, globe_dots, inset, squash_paths
from .errors import StippleError

FORMATS = (".csv", ".svg", ".png", ".geojson", ".json")
UNITS = {"mm": 1.0, "cm": 10.0, "in": 25.4, "px": 25.4 / 96}
SUPERSAMPLE = 4


def output_format(path):
    """The format of ``path`` by its extension (``-`` is CSV on stdout)."""
    if str(path) == "-":
        return ".csv"
    extension = os.path.splitext(str(path))[1].lower()
    if extension not in FORMATS:
        raise StippleError(f"{path}: unknown output format {extension or '(none)'}; use one of {', '.join(FORMATS)}")
    return extension


def check_writable(path):
    """Raise if the directory of ``path`` cannot take a new file (checked before a long run)."""
    if str(path) == "-":
        if sys.stdout is None:
            raise StippleError("cannot write to stdout: it is closed")
        return
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise StippleError(f"{path}: directory {directory} does not exist")
    if os.path.isdir(path):
        raise StippleError(f"{path}: is a directory")
    if os.path.exists(path) and not os.stat(path).st_mode & 0o222:
        raise StippleError(f"{path}: is read-only; make it writable or choose another name")
    try:
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError as error:
        raise StippleError(f"{path}: not writable ({error.strerror})") from None


def atomic_write(path, data):
    """Write ``data`` (bytes) to ``path`` so that readers see the old file or the whole new one."""
    commit_outputs([(path, data)])


def commit_outputs(items):
    """Write every ``(path, bytes)`` of ``items`` all-or-nothing (``-`` is stdout).

    Each file is first written to a temporary file beside it (flushed and fsynced); only when all of
    them are written (and stdout has taken its share) are they renamed over their targets, with SIGINT
    and SIGTERM held back during the renames. Any failure or signal before that removes every temporary
    file and leaves every existing output as it was.
    """
    temporaries = []
    try:
        for path, data in items:
            if str(path) != "-":
                temporaries.append((_write_temporary(path, data), path))
        for path, data in items:
            if str(path) == "-":
                write_stdout(data)
        with _signals_held():
            while temporaries:
                temporary, path = temporaries[0]
                try:
                    os.replace(temporary, path)
                except OSError as error:
                    raise StippleError(f"{path}: cannot write ({error.strerror})") from None
                temporaries.pop(0)
    finally:
        for temporary, _ in temporaries:
            _remove(temporary)


def _write_temporary(path, data):
    """A fsynced temporary file in the directory of ``path`` holding ``data``, with the mode ``path`` will get."""
    directory = os.path.dirname(os.path.abspath(path))
    try:
        handle, temporary = tempfile.mkstemp(dir=directory, prefix=".stipple-", suffix=".tmp")
    except OSError as error:
        raise StippleError(f"{path}: cannot write ({error.strerror})") from None
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        mode = os.stat(path).st_mode & 0o777 if os.path.exists(path) else 0o666 & ~_umask()
        os.chmod(temporary, mode)
    except BaseException as error:
        _remove(temporary)
        if isinstance(error, OSError):
            raise StippleError(f"{path}: cannot write ({error.strerror or error})") from None
        raise
    return temporary


def _remove(path):
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass


@contextlib.contextmanager
def _signals_held():
    """SIGINT and SIGTERM received in the block are delivered after it (main thread only; else a no-op).

    The Python-level handlers are swapped for a recorder, which works whichever thread the kernel
    picks for the signal; recorded signals are raised again once the previous handlers are back.
    """
    caught = []
    previous = {}
    try:
        for number in (signal.SIGINT, signal.SIGTERM):
            previous[number] = signal.signal(number, lambda number, frame: caught.append(number))
    except ValueError:  # not the main thread: signals cannot be handled here anyway
        pass
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, signal.SIG_DFL if handler is None else handler)
        for number in dict.fromkeys(caught):
            signal.raise_signal(number)


def write_stdout(data):
    """Write ``data`` (bytes) to stdout; a closed or full stdout is a StippleError, not a traceback."""
    stream = sys.stdout
    if stream is None:
        raise StippleError("cannot write to stdout: it is closed")
    try:
        stream.flush()
        stream.buffer.write(data)
        stream.buffer.flush()
    except (OSError, ValueError) as error:
        _discard_stdout()
        raise StippleError(f"cannot write to stdout ({getattr(error, 'strerror', None) or error})") from None


def _discard_stdout():
    """Point stdout at /dev/null so that the interpreter's final flush cannot fail a second time."""
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)
    except (OSError, ValueError, AttributeError):
        pass


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


MIN_LENGTH_MM = 1e-3
MAX_LENGTH_MM = 1e6


def parse_length(text, name="length"):
    """``"200mm"``, ``"8in"``, ``"20 cm"``, ``"800px"`` or a bare number (mm) -> (value, unit).

    The length must lie between ``MIN_LENGTH_MM`` (1 µm) and ``MAX_LENGTH_MM`` (1 km).
    """
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(mm|cm|in|px)?\s*", str(text))
    allowed = f"a number with a unit (mm, cm, in, px) from {MIN_LENGTH_MM:g}mm to {MAX_LENGTH_MM:g}mm"
    if not match:
        raise StippleError(f"{name} must be {allowed}, not {text!r}")
    value, unit = float(match.group(1)), match.group(2) or "mm"
    if not MIN_LENGTH_MM <= value * UNITS[unit] <= MAX_LENGTH_MM:
        raise StippleError(f"{name} must be {allowed}, not {text!r}")
    return value, unit


def csv_bytes(columns, names, number_format=".6f"):
    """CSV with a header row; a fixed number format so that output is byte-stable (".17g" round-trips)."""
    lines = [",".join(names)]
    table = np.column_stack(columns)
    lines.extend(",".join(format(value, number_format) for value in row) for row in table)
    return ("\n".join(lines) + "\n").encode()


MAX_CANVAS_SIDE = 1 << 20


def png_canvas(size, pixels_wide):
    """Scale and ``(width, height)`` of the supersampled canvas for a PNG ``pixels_wide`` wide of ``size``."""
    width, height = size
    scale = pixels_wide / width * SUPERSAMPLE
    return scale, (int(round(width * scale)), int(round(height * scale)))


def check_png_canvas(size, pixels_wide, layers=2):
    """Refuse a PNG whose drawing canvas is too large for a side limit or for the memory available.

    ``layers`` counts the canvas-sized images alive at once (the canvas and a background).
    """
    from .halftone import available_memory

    _, (columns, rows) = png_canvas(size, pixels_wide)
    picture = f"a PNG {pixels_wide} pixels wide of a {size[0]:g}×{size[1]:g} canvas"
    if max(columns, rows) > MAX_CANVAS_SIDE:
        raise StippleError(
            f"{picture} would be {columns // SUPERSAMPLE}×{rows // SUPERSAMPLE} pixels, more than "
            f"{MAX_CANVAS_SIDE // SUPERSAMPLE} per side: use a smaller --png-width, or SVG"
        )
    if min(columns, rows) < SUPERSAMPLE:
        raise StippleError(f"{picture} would be less than one pixel high or wide: use a larger --png-width, or SVG")
    needed, available = columns * rows * layers * 1.1, available_memory()
    if needed > available:
        raise StippleError(
            f"{picture} needs about {needed / 2**30:.1f} GiB of memory to draw, more than the "
            f"{available / 2**30:.1f} GiB available: use a smaller --png-width, or SVG"
        )


def png_bytes(image):
    buffer = io.BytesIO()
    image.save(buffer, format="PNG", optimize=False)
    return buffer.getvalue()


def geojson_bytes(lon_lat, properties=None):
    """A FeatureCollection with one MultiPoint feature (lon, lat in degrees)."""
    feature = {
        "type": "Feature",
        "properties": properties or {},
        "geometry": {"type": "MultiPoint", "coordinates": np.round(lon_lat, 7).tolist()},
    }
    return (json.dumps({"type": "FeatureCollection", "features": [feature]}) + "\n").encode()


def to_user_units(length, physical_width, canvas_width):
    """A physical ``(value, unit)`` length in user units of a canvas ``physical_width`` wide."""
    value, unit = length
    width_value, width_unit = physical_width
    return value * UNITS[unit] / (width_value * UNITS[width_unit]) * canvas_width


def ink_radius(ink_area, count):
    """Radius at which ``count`` discs cover ``ink_area`` (the density's mass): the mean tone is kept."""
    return float(np.sqrt(ink_area / (np.pi * count)))


def default_png_width(count):
    return int(max(1024, 8 * round(np.sqrt(count) / 2)))


def check_png_outputs(formats, canvas, png_width, count):
    """Before a run: refuse PNG outputs whose canvas (user units ``(width, height)``) would not fit in memory."""
    if ".png" in formats:
        check_png_canvas(canvas, png_width or default_png_width(count))


ORTHO_SIZE = 1000.0
PROJECTIONS = ("ortho", "equirect")


def sphere_canvas(projection, fmt=".png"):
    """``(width, height)`` in user units of a sphere picture (SVG or PNG): the equirectangular map or the globe."""
    if projection == "equirect":
        return (ORTHO_SIZE * 2, ORTHO_SIZE)
    return (ORTHO_SIZE, ORTHO_SIZE)


GLOBE = 0.98  # the globe's radius over half the canvas


def orthographic(points, view):
    """Canvas positions (``ORTHO_SIZE`` square, y down) of unit vectors seen from ``view``, and their depth
    (cosine of the angle from the view's centre; positive on the visible side)."""
    lon, lat = np.radians(view)
    centre = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(centre, east)
    half = ORTHO_SIZE / 2
    xy = np.stack([half + GLOBE * half * (points @ east), half - GLOBE * half * (points @ north)], axis=1)
    return xy, points @ centre


def equirectangular(longitude, latitude, width):
    """Canvas positions of (lon, lat) degrees on a ``width × width/2`` canvas, lon -180 at the left."""
    return np.stack([(longitude + 180) / 360 * width, (90 - latitude) / 180 * width / 2], axis=1)


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


# One-line drawings (``stipple line``): a closed polyline in pixel units of the input image.


def render_line(pixels, size, pixels_wide, pen_width, closed=True):
    """An antialiased grayscale image of a black polyline of ``pen_width`` (user units) on white.

    ``pixels`` are the vertices in user units of a canvas of ``size = (width, height)``; drawn at 4× and reduced.
    """
    width, height = size
    scale = pixels_wide / width * SUPERSAMPLE
    canvas = Image.new("L", (int(round(width * scale)), int(round(height * scale))), 255)
    vertices = np.asarray(pixels) * scale
    if closed:
        vertices = np.vstack([vertices, vertices[:1]])
    stroke = max(int(round(pen_width * scale)), 1)
    ImageDraw.Draw(canvas).line([tuple(v) for v in vertices], fill=0, width=stroke, joint="curve")
    return canvas.reduce(SUPERSAMPLE)


def line_svg_bytes(pixels, size, physical_width, pen_width, comment=""):
    """One closed ``<path>`` (``M x y L ... Z``) stroked ``pen_width`` user units wide, unfilled."""
    width, height = size
    value, unit = physical_width
    points = " ".join(f"{x:.3f},{y:.3f}" for x, y in pixels)
    return "\n".join(
        [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{value:g}{unit}" '
            f'height="{value * height / width:.6g}{unit}" viewBox="0 0 {width:g} {height:g}">',
            f"<!-- {comment} -->" if comment else "",
            f'<path fill="none" stroke="black" stroke-width="{pen_width:.4f}" stroke-linejoin="round" '
            f'd="M {points} Z"/>',
            "</svg>\n",
        ]
    ).encode()


def line_output(points, shape, fmt, *, width=(200.0, "mm"), pen_width=None, png_width=None):
    """Bytes of a closed curve (vertices in unit coordinates, path order) in ``fmt``.

    CSV is ``x,y`` in pixel units in path order (the closing segment from the last vertex back to the first is
    implied); SVG one closed ``<path>`` of physical ``width`` stroked ``pen_width`` (physical ``(value, unit)``,
    default one input pixel); PNG the same line, ``png_width`` pixels wide (default: the input's width × 4).
    """
    rows, columns = shape
    pixels = np.asarray(points) * np.array([columns, rows])
    if fmt == ".csv":
        return csv_bytes([pixels[:, 0], pixels[:, 1]], ["x", "y"])
    if fmt in (".geojson", ".json"):
        raise StippleError("GeoJSON output is for sphere points")
    stroke = 1.0 if pen_width is None else to_user_units(pen_width, width, columns)
    if fmt == ".svg":
        return line_svg_bytes(
            pixels, (columns, rows), width, stroke, comment=f"one closed line, {len(pixels)} vertices"
        )
    return png_bytes(render_line(pixels, (columns, rows), png_width or 4 * columns, stroke))


# Layered (multi-class) output: one layer per ink, as plotters and vpype expect (one pen per layer).


def hex_colour(colour):
    """``#rrggbb`` of an RGB triple in [0, 1]."""
    return "#" + "".join(f"{int(round(255 * channel)):02x}" for channel in colour)


def layered_csv_bytes(pixels, layer_names):
    """CSV ``x,y,layer`` with one row per dot; ``layer_names`` holds each dot's layer name."""
    lines = ["x,y,layer"]
    lines.extend(f"{x:.6f},{y:.6f},{name}" for (x, y), name in zip(pixels, layer_names, strict=True))
    return ("\n".join(lines) + "\n").encode()


def path_data(path):
    """SVG path data of a polyline given as complex vertices."""
    return "M" + " L".join(f"{z.real:.4f},{z.imag:.4f}" for z in path)


WHITE, BLACK = (1.0, 1.0, 1.0), (0.0, 0.0, 0.0)


def parse_colour(text, name="color"):
    """``#rrggbb``, ``#rgb`` or a CSS colour name (``white``, ``navy``) -> RGB in [0, 1]."""
    from PIL import ImageColor

    try:
        rgb = ImageColor.getrgb(str(text).strip())
    except ValueError:
        raise StippleError(f"{name} must be a colour such as #1a2b3c, #fff or white, not {text!r}") from None
    return tuple(channel / 255 for channel in rgb[:3])


def svg_document(layers, size, physical_width, *, background=WHITE, pen_width=None, notes=()):
    """SVG of ``Dots`` layers, one Inkscape layer each, on a ``size = (width, height)`` user-unit canvas.

    Round dots are circles, foreshortened ones ellipses, pen-drawn ones stroked paths ``pen_width`` wide.
    Filled dots also carry a stroke of their colour (width 0), so that ``vpype read`` keeps each layer's pen
    colour. ``notes`` become comments and the ``<desc>``; a background other than white is a filled rectangle.
    """
    width, height = size
    value, unit = physical_width
    parts = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        f'width="{value:g}{unit}" height="{value * height / width:.6g}{unit}" viewBox="0 0 {width:g} {height:g}">',
    ]
    parts.extend(f"<!-- {note} -->" for note in notes)
    if notes:
        parts.append(f"<desc>{'; '.join(notes)}</desc>")
    if tuple(background) != WHITE:
        parts.append(f'<rect x="0" y="0" width="{width:g}" height="{height:g}" fill="{hex_colour(background)}"/>')
    for index, dots in enumerate(layers, start=1):
        parts.append(_svg_layer(index, dots, pen_width))
    parts.append("</svg>\n")
    return "\n".join(parts).encode()


def _svg_layer(index, dots, pen_width):
    colour = hex_colour(dots.colour)
    label = f'id="layer{index}" inkscape:groupmode="layer" inkscape:label="{index}-{dots.name}"'
    if dots.paths is not None:
        head = (
            f'<g {label} fill="none" stroke="{colour}" stroke-width="{pen_width:.4f}" '
            'stroke-linecap="round" stroke-linejoin="round">'
        )
        body = [f'<path d="{path_data(path)}"/>' for path in dots.paths]
    elif dots.squash is None:
        head = f'<g {label} fill="{colour}" stroke="{colour}" stroke-width="0">'
        body = [
            f'<circle cx="{x:.4f}" cy="{y:.4f}" r="{r:.4f}"/>'
            for (x, y), r in zip(dots.centres, dots.radii, strict=True)
        ]
    else:
        head = f'<g {label} fill="{colour}" stroke="{colour}" stroke-width="0">'
        body = [
            f'<ellipse cx="{x:.4f}" cy="{y:.4f}" rx="{r * s:.4f}" ry="{r:.4f}" '
            f'transform="rotate({np.degrees(a):.2f} {x:.4f} {y:.4f})"/>'
            for (x, y), r, s, a in zip(dots.centres, dots.radii, dots.squash, dots.angle, strict=True)
        ]
    return "\n".join([head, *body, "</g>"])


def render_picture(layers, size, pixels_wide, *, background=WHITE, pen_width=None, blend="over", underlay=None):
    """An antialiased PNG picture (``PIL.Image``) of ``Dots`` layers, drawn at 4× and box-filtered.

    ``blend`` "over" paints each layer's colour over what is below (one ink on any background); "multiply"
    prints inks on paper (overlapping cyan and yellow make green). ``underlay(draw, scale)`` may draw on a
    coverage mask first (the globe's outline), which is painted 8 % of the way from the background to the
    first layer's colour. The picture is grayscale when every colour is a gray.
    """
    check_png_canvas(size, pixels_wide)
    scale, canvas_size = png_canvas(size, pixels_wide)
    picture = np.empty((canvas_size[1], canvas_size[0], 3))
    picture[:] = background
    if underlay is not None and layers:
        mask = Image.new("L", canvas_size, 0)
        underlay(ImageDraw.Draw(mask), scale)
        coverage = np.asarray(mask, dtype=np.float64)[..., None] / 255.0 * 0.08
        picture += coverage * (np.asarray(layers[0].colour) - picture)
    for dots in layers:
        coverage = np.asarray(_coverage(dots, canvas_size, scale, pen_width), dtype=np.float64)[..., None] / 255.0
        colour = np.asarray(dots.colour)
        target = picture * colour if blend == "multiply" else colour
        picture += coverage * (target - picture)
    image = Image.fromarray(np.round(np.clip(picture, 0, 1) * 255).astype(np.uint8), "RGB")
    if all(len(set(c)) == 1 for c in [tuple(background)] + [tuple(d.colour) for d in layers]):
        image = image.convert("L")
    return image.reduce(SUPERSAMPLE)


def _coverage(dots, canvas_size, scale, pen_width):
    """A mask (``PIL.Image`` "L") of the ink of one layer of dots on the supersampled canvas."""
    mask = Image.new("L", canvas_size, 0)
    draw = ImageDraw.Draw(mask)
    if dots.paths is not None:
        stroke = max(int(round(pen_width * scale)), 1)
        for path in dots.paths:
            draw.line([(z.real * scale, z.imag * scale) for z in path], fill=255, width=stroke, joint="curve")
    elif dots.squash is None:
        for (x, y), radius in zip(np.asarray(dots.centres) * scale, np.maximum(dots.radii * scale, 0.5), strict=True):
            draw.ellipse((x - radius, y - radius, x + radius, y + radius), fill=255)
    else:
        for centre, radius, squash, angle in zip(
            dots.centres * scale, dots.radii * scale, dots.squash, dots.angle, strict=True
        ):
            draw.polygon(
                ellipse_polygon(centre, max(radius, 0.5), max(squash, 0.5 / max(radius, 0.5)), angle), fill=255
            )
    return mask


def with_pen_paths(layers, dot_style, pen):
    """The layers with pen paths (``stipple.plotter.dot_paths``) for a pen style; unchanged for "disc"."""
    from .plotter import dot_paths

    if dot_style == "disc":
        return layers
    for dots in layers:
        dots.paths = squash_paths(dot_paths(dots.centres, dots.radii, dot_style, pen), dots)
    return layers


def _look(width, columns, dot_radius, dot_style, pen_width):
    """The fixed radius (user units, or None for the default) and the pen width in user units."""
    radius = None if dot_radius is None else to_user_units(dot_radius, width, columns)
    pen = to_user_units(pen_width, width, columns)
    return radius, (pen if dot_style != "disc" else None), pen


def draw_layers(layers, fmt, size, *, width, png_width, count, pen, background=WHITE, blend="over", notes=()):
    """SVG or PNG bytes of ``Dots`` layers."""
    if fmt == ".svg":
        return svg_document(layers, size, width, background=background, pen_width=pen, notes=notes)
    picture = render_picture(
        layers, size, png_width or default_png_width(count), background=background, pen_width=pen, blend=blend
    )
    return png_bytes(picture)


def torus_output(points, shape, fmt, **options):
    """Bytes of torus ``points`` (unit coordinates) in ``fmt`` for an image of ``shape = (H, W)``: one layer
    of dots in ``color`` on ``background`` (see ``layered_torus_output``; CSV is ``x,y`` in pixels)."""
    if fmt == ".csv":
        rows, columns = shape
        pixels = points * np.array([columns, rows])
        return csv_bytes([pixels[:, 0], pixels[:, 1]], ["x", "y"])
    color = options.pop("color", BLACK)
    return layered_torus_output([("dots", color, points)], shape, fmt, blend="over", **options)


def layered_torus_output(
    layers,
    shape,
    fmt,
    *,
    width=(200.0, "mm"),
    dot_radius=None,
    png_width=None,
    ink=None,
    dot_style="disc",
    pen_width=(0.3, "mm"),
    background=WHITE,
    blend="multiply",
):
    """Bytes of layered torus dots in ``fmt``; ``layers`` are ``(name, colour, points)`` with points in unit
    coordinates of an image of ``shape = (H, W)``.

    CSV is ``x,y,layer`` in pixels; SVG one Inkscape layer per ink; PNG the inks printed on ``background``.
    Drawings are inset by the largest radius so that no dot crosses the canvas's edge (the CSV keeps the
    exact positions). The default radius of a dot is the one that makes the dots' ink equal ``ink`` (the
    density's mean; 0.5 if unknown), capped at 0.45 × its distance to the nearest dot of any layer
    (``stipple.drawing``); ``dot_radius`` (physical ``(value, unit)``) fixes it. ``dot_style`` "disc" draws
    filled discs; "circle", "filled" and "point" pen paths ``pen_width`` wide (a plotter preview in the PNG).
    """
    rows, columns = shape
    count = sum(len(points) for _, _, points in layers)
    placed = [(name, colour, points * np.array([columns, rows])) for name, colour, points in layers]
    if fmt == ".csv":
        pixels = np.concatenate([centres for _, _, centres in placed])
        names = [name for name, _, centres in placed for _ in range(len(centres))]
        return layered_csv_bytes(pixels, names)
    if fmt in (".geojson", ".json"):
        raise StippleError("GeoJSON output is for sphere points")
    radius, stroke, pen = _look(width, columns, dot_radius, dot_style, pen_width)
    tone = ink_radius((0.5 if ink is None else ink) * rows * columns, max(count, 1))
    drawn = flat_dots(placed, (columns, rows), tone_radius=tone, radius=radius, pen=stroke)
    drawn = with_pen_paths(drawn, dot_style, pen)
    notes = [f"{count} dots in {len(drawn)} layer(s), inset {_margin(drawn, stroke):.4g} user units from the edges"]
    return draw_layers(
        drawn,
        fmt,
        (columns, rows),
        width=width,
        png_width=png_width,
        count=count,
        pen=pen,
        background=background,
        blend=blend,
        notes=notes,
    )


def _margin(layers, pen):
    """The largest radius drawn (or half the pen), for the SVG's note."""
    radii = [dots.radii.max() for dots in layers if len(dots.radii)]
    return max(radii + [(pen or 0.0) / 2])


def sphere_output(
    points,
    lon_lat,
    fmt,
    *,
    coords="lonlat",
    projection="ortho",
    view=(0.0, 0.0),
    width=(200.0, "mm"),
    dot_radius=None,
    png_width=None,
    ink=None,
    color=BLACK,
    background=WHITE,
    dot_style="disc",
    pen_width=(0.3, "mm"),
):
    """Bytes of sphere ``points`` (unit vectors; ``lon_lat`` their degrees) in ``fmt``.

    CSV is ``lon,lat`` in degrees or ``x,y,z``; GeoJSON a MultiPoint. SVG and PNG draw ``projection``:
    "equirect" every dot on the 2:1 map (inset from the edges like torus dots), "ortho" the visible side of
    the globe around ``view = (lon, lat)``, each dot foreshortened towards the limb (an ellipse), so the limb
    keeps its tone; the SVG says how many dots are on the visible side. The default angular radius keeps the
    tone (``ink`` of the sphere, 0.5 if unknown), capped at 0.45 × the great-circle distance to the nearest dot.
    """
    longitude, latitude = lon_lat
    if fmt == ".csv":
        if coords == "xyz":
            return csv_bytes(list(points.T), ["x", "y", "z"], number_format=".17g")
        # Round-trip digits: 6 decimals of a degree would cap a spherical design's error near 6e-8.
        return csv_bytes([longitude, latitude], ["lon", "lat"], number_format=".17g")
    if fmt in (".geojson", ".json"):
        return geojson_bytes(np.stack([longitude, latitude], axis=1), {"points": len(points)})
    canvas = sphere_canvas(projection)
    fixed, stroke, pen = _look(width, canvas[0], dot_radius, dot_style, pen_width)
    per_radian = canvas[0] / (2 * np.pi) if projection == "equirect" else GLOBE * ORTHO_SIZE / 2
    tone = 2 * np.sqrt((0.5 if ink is None else ink) / max(len(points), 1))
    angles = (
        capped_radii(angular_distances(points), tone) if fixed is None else np.full(len(points), fixed / per_radian)
    )
    if projection == "equirect":
        centres, margin = inset(
            equirectangular(longitude, latitude, canvas[0]), canvas, per_radian * angles.max(initial=0)
        )
        drawn = Dots("dots", color, centres, np.minimum(angles * per_radian, margin))
        notes = [f"{len(points)} dots, equirectangular (all of them)"]
    else:
        centres, depth = orthographic(points, view)
        visible = depth > 0
        half = ORTHO_SIZE / 2
        drawn = globe_dots("dots", color, centres[visible], depth[visible], angles[visible], per_radian, (half, half))
        notes = [
            f"{int(visible.sum())} of {len(points)} dots on the visible side (orthographic, view "
            f"{view[0]:g},{view[1]:g}; dots foreshortened towards the limb)"
        ]
    layers = with_pen_paths([drawn], dot_style, pen)
    if fmt == ".svg":
        return svg_document(layers, canvas, width, background=background, pen_width=pen, notes=notes)
    picture = render_picture(
        layers,
        canvas,
        png_width or default_png_width(len(points)),
        background=background,
        pen_width=pen,
        underlay=_globe_outline if projection == "ortho" else None,
    )
    return png_bytes(picture)


def _globe_outline(draw, scale):
    """The globe's disc, marking its outline on the PNG."""
    low, high = (1 - GLOBE) / 2 * ORTHO_SIZE * scale, (1 + GLOBE) / 2 * ORTHO_SIZE * scale
    draw.ellipse((low, low, high, high), fill=255)
