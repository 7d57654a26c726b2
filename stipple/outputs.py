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


def svg_bytes(centres, size, physical_width, radius, comment=""):
    """Filled circles at ``centres`` in a ``size = (width, height)`` user-unit canvas.

    ``physical_width`` is ``(value, unit)``; ``radius`` in user units.
    """
    width, height = size
    value, unit = physical_width
    physical_height = value * height / width
    parts = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{value:g}{unit}" height="{physical_height:.6g}{unit}" '
        f'viewBox="0 0 {width:g} {height:g}">',
    ]
    if comment:
        parts.append(f"<!-- {comment} -->")
    parts.append('<g fill="black" stroke="none">')
    parts.extend(f'<circle cx="{x:.4f}" cy="{y:.4f}" r="{radius:.4f}"/>' for x, y in centres)
    parts.append("</g>\n</svg>\n")
    return "\n".join(parts).encode()


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


def render_dots(centres, size, pixels_wide, radius, background=None):
    """An antialiased grayscale PNG of black discs on white (or on ``background``, a PIL image).

    ``centres`` and ``radius`` are in user units of a canvas of ``size = (width, height)``; the picture
    is ``pixels_wide`` pixels wide, drawn at 4× and reduced with a box filter. The canvas's memory is
    checked before it is allocated.
    """
    check_png_canvas(size, pixels_wide)
    scale, canvas_size = png_canvas(size, pixels_wide)
    canvas = Image.new("L", canvas_size, 255)
    if background is not None:
        canvas.paste(background.resize(canvas_size, Image.BILINEAR))
    draw = ImageDraw.Draw(canvas)
    r = max(radius * scale, 0.5)
    for x, y in np.asarray(centres) * scale:
        draw.ellipse((x - r, y - r, x + r, y + r), fill=0)
    return canvas.reduce(SUPERSAMPLE)


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


def torus_output(points, shape, fmt, *, width=(200.0, "mm"), dot_radius=None, png_width=None, ink=None):
    """Bytes of torus ``points`` (unit coordinates) in ``fmt`` for an image of ``shape = (H, W)``.

    CSV is ``x,y`` in pixel units (origin top-left, y down). SVG and PNG draw discs of
    ``dot_radius`` (physical ``(value, unit)``) or, by default, of the radius at which the dots' ink
    equals ``ink`` (the density's mean, 0..1; half the image if unknown).
    """
    rows, columns = shape
    pixels = points * np.array([columns, rows])
    if fmt == ".csv":
        return csv_bytes([pixels[:, 0], pixels[:, 1]], ["x", "y"])
    if fmt in (".geojson", ".json"):
        raise StippleError("GeoJSON output is for sphere points")
    if dot_radius is None:
        radius = ink_radius((0.5 if ink is None else ink) * rows * columns, len(points))
    else:
        radius = to_user_units(dot_radius, width, columns)
    if fmt == ".svg":
        return svg_bytes(pixels, (columns, rows), width, radius, comment=f"{len(points)} dots")
    return png_bytes(render_dots(pixels, (columns, rows), png_width or default_png_width(len(points)), radius))


ORTHO_SIZE = 1000.0
PROJECTIONS = ("ortho", "equirect")


def sphere_canvas(projection, fmt=".png"):
    """``(width, height)`` in user units of a sphere picture: the equirectangular map or the globe."""
    if projection == "equirect" and fmt == ".png":
        return (ORTHO_SIZE * 2, ORTHO_SIZE)
    return (ORTHO_SIZE, ORTHO_SIZE)


def orthographic(points, view):
    """Canvas positions (``ORTHO_SIZE`` square, y down) and visibility of unit vectors seen from ``view``."""
    lon, lat = np.radians(view)
    centre = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(centre, east)
    half = ORTHO_SIZE / 2
    xy = np.stack([half + 0.98 * half * (points @ east), half - 0.98 * half * (points @ north)], axis=1)
    return xy, points @ centre > 0


def equirectangular(longitude, latitude, width):
    """Canvas positions of (lon, lat) degrees on a ``width × width/2`` canvas, lon -180 at the left."""
    return np.stack([(longitude + 180) / 360 * width, (90 - latitude) / 180 * width / 2], axis=1)


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
):
    """Bytes of sphere ``points`` (unit vectors; ``lon_lat`` their degrees) in ``fmt``.

    CSV is ``lon,lat`` in degrees or ``x,y,z``; GeoJSON a MultiPoint; SVG the orthographic front
    hemisphere around ``view = (lon, lat)``; PNG that view or the equirectangular map. Discs have
    ``dot_radius`` (physical) or by default the radius at which the dots' ink equals ``ink`` of the sphere.
    """
    longitude, latitude = lon_lat
    if fmt == ".csv":
        if coords == "xyz":
            return csv_bytes(list(points.T), ["x", "y", "z"], number_format=".17g")
        # Round-trip digits: 6 decimals of a degree would cap a spherical design's error near 6e-8.
        return csv_bytes([longitude, latitude], ["lon", "lat"], number_format=".17g")
    if fmt in (".geojson", ".json"):
        return geojson_bytes(np.stack([longitude, latitude], axis=1), {"points": len(points)})
    angular_radius = 2 * np.sqrt((0.5 if ink is None else ink) / len(points))
    canvas = sphere_canvas(projection, fmt)
    if projection == "equirect" and fmt == ".png":
        centres = equirectangular(longitude, latitude, canvas[0])
        radius = angular_radius * canvas[0] / (2 * np.pi)
    else:
        centres, visible = orthographic(points, view)
        centres = centres[visible]
        radius = angular_radius * 0.98 * ORTHO_SIZE / 2
    if dot_radius is not None:
        radius = to_user_units(dot_radius, width, canvas[0])
    if fmt == ".svg":
        return svg_bytes(centres, canvas, width, radius, comment=f"{len(centres)} of {len(points)} dots, front")
    return png_bytes(
        render_dots(
            centres,
            canvas,
            png_width or default_png_width(len(points)),
            radius,
            background=_globe_background(canvas) if projection == "ortho" else None,
        )
    )


def _globe_background(canvas):
    """A light disc marking the globe's outline."""
    image = Image.new("L", (int(canvas[0]), int(canvas[1])), 255)
    half = ORTHO_SIZE / 2
    ImageDraw.Draw(image).ellipse(
        (half * 0.02, half * 0.02, ORTHO_SIZE - half * 0.02, ORTHO_SIZE - half * 0.02), fill=235
    )
    return image


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


def layered_svg_bytes(layers, size, physical_width, radius=None, pen_width=None):
    """SVG with one Inkscape layer (``<g>``) per ``(name, colour, centres, paths)`` in ``layers``.

    Layers without ``paths`` are filled circles of ``radius``; with ``paths`` (pen paths from
    ``stipple.plotter.dot_paths``) they are stroked polylines ``pen_width`` wide. All in user units of a
    ``size = (width, height)`` canvas; ``physical_width`` is ``(value, unit)``.
    """
    width, height = size
    value, unit = physical_width
    parts = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        f'width="{value:g}{unit}" height="{value * height / width:.6g}{unit}" viewBox="0 0 {width:g} {height:g}">',
    ]
    for index, (name, colour, centres, paths) in enumerate(layers, start=1):
        label = f'id="layer{index}" inkscape:groupmode="layer" inkscape:label="{index}-{name}"'
        if paths is None:
            parts.append(f'<g {label} fill="{hex_colour(colour)}" stroke="none">')
            parts.extend(f'<circle cx="{x:.4f}" cy="{y:.4f}" r="{radius:.4f}"/>' for x, y in centres)
        else:
            parts.append(
                f'<g {label} fill="none" stroke="{hex_colour(colour)}" stroke-width="{pen_width:.4f}" '
                'stroke-linecap="round" stroke-linejoin="round">'
            )
            parts.extend(f'<path d="{path_data(path)}"/>' for path in paths)
        parts.append("</g>")
    parts.append("</svg>\n")
    return "\n".join(parts).encode()


def render_layers(layers, size, pixels_wide, radius=None, pen_width=None):
    """An RGB picture of inks on white paper: each layer's coverage (discs, or its pen paths stroked
    ``pen_width`` wide) multiplies the paper by the ink's colour, so overlapping cyan and yellow print green."""
    width, height = size
    scale = pixels_wide / width * SUPERSAMPLE
    canvas_size = (int(round(width * scale)), int(round(height * scale)))
    picture = np.ones((canvas_size[1], canvas_size[0], 3))
    for _, colour, centres, paths in layers:
        mask = Image.new("L", canvas_size, 0)
        draw = ImageDraw.Draw(mask)
        if paths is None:
            r = max(radius * scale, 0.5)
            for x, y in np.asarray(centres) * scale:
                draw.ellipse((x - r, y - r, x + r, y + r), fill=255)
        else:
            stroke = max(int(round(pen_width * scale)), 1)
            for path in paths:
                draw.line([(z.real * scale, z.imag * scale) for z in path], fill=255, width=stroke, joint="curve")
        coverage = np.asarray(mask, dtype=np.float64)[..., None] / 255.0
        picture *= 1.0 - coverage * (1.0 - np.asarray(colour))
    image = Image.fromarray(np.round(picture * 255).astype(np.uint8), "RGB")
    return image.reduce(SUPERSAMPLE)


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
):
    """Bytes of layered torus dots in ``fmt``; ``layers`` are ``(name, colour, points)`` with points in unit
    coordinates of an image of ``shape = (H, W)``.

    CSV is ``x,y,layer`` in pixels; SVG one layer per ink; PNG the inks printed on white. The default dot
    radius makes the dots' ink equal to ``ink`` (the union density's mean; 0.5 if unknown). ``dot_style``
    "disc" draws filled circles; "circle", "filled" and "point" draw pen paths (``stipple.plotter.dot_paths``)
    of ``pen_width`` (physical ``(value, unit)``), in the SVG and in the PNG, which is then a plotter preview.
    """
    from .plotter import dot_paths

    rows, columns = shape
    count = sum(len(points) for _, _, points in layers)
    placed = [(name, colour, points * np.array([columns, rows])) for name, colour, points in layers]
    if fmt == ".csv":
        pixels = np.concatenate([centres for _, _, centres in placed])
        names = [name for name, _, centres in placed for _ in range(len(centres))]
        return layered_csv_bytes(pixels, names)
    if fmt in (".geojson", ".json"):
        raise StippleError("GeoJSON output is for sphere points")
    if dot_radius is None:
        radius = ink_radius((0.5 if ink is None else ink) * rows * columns, count)
    else:
        radius = to_user_units(dot_radius, width, columns)
    pen = to_user_units(pen_width, width, columns)
    drawn = [
        (name, colour, centres, None if dot_style == "disc" else dot_paths(centres, radius, dot_style, pen))
        for name, colour, centres in placed
    ]
    if fmt == ".svg":
        return layered_svg_bytes(drawn, (columns, rows), width, radius, pen)
    return png_bytes(render_layers(drawn, (columns, rows), png_width or default_png_width(count), radius, pen))
