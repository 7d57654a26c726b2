"""The pen paths of an SVG, as a pen plotter sees them: per layer, polylines in millimetres, in document order.

Reads any SVG that stipple or ``vpype write`` produces (and most others): layers are the root's top-level
groups (Inkscape layers or not, as ``vpype read`` takes them), shapes outside any group form a layer of their
own; ``path`` (lines, Bézier curves, arcs), ``polyline``, ``polygon``, ``line``, ``rect``, ``circle`` and
``ellipse`` become polylines, with the ``transform`` of every enclosing group applied. A path's every ``M`` starts
a new pen-down stroke. Curves and round shapes are flattened finely enough that a circle's length is within
``1e-4`` of ``2 pi r``. Documents that declare entities are refused: nothing is expanded (a plain ``DOCTYPE``
naming the SVG 1.1 DTD is read; the DTD is never fetched).
"""

import re
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass

import numpy as np

from ..errors import StippleError
from .plot_svg_path import path_strokes
from .sources import read_source
from .units import DECIMAL, UNITS

MAX_SVG_BYTES = 1 << 28
ROUND_SEGMENTS = 256
# Groups nested deeper are refused (5000 of them overflowed Python's stack), and so are vertices farther from the
# origin than this many millimetres (10 km; 1e308 made the lengths infinite and the estimate failed).
MAX_GROUP_DEPTH, MAX_COORDINATE_MM = 200, 1e7
MM_PER = {**UNITS, "pc": 25.4 / 6, "": UNITS["px"]}  # SVG lengths: the options' units, picas, bare user units
SVG = "{http://www.w3.org/2000/svg}"
INKSCAPE_LABEL = "{http://www.inkscape.org/namespaces/inkscape}label"
SKIPPED = {"defs", "metadata", "title", "desc", "style", "clipPath", "mask", "symbol", "marker", "pattern"}


@dataclass
class PenLayer:
    """One pen: its name and its strokes, each a complex vertex array ``x + iy`` in millimetres (y down)."""

    name: str
    paths: list


def read_pen_layers(source):
    """The ``PenLayer``s of the SVG file ``source`` (a path or a binary stream), in document order.

    Raises
    ------
    StippleError
        If the file is not a readable SVG (one line naming the problem).
    """
    name = str(getattr(source, "name", source))
    data = read_source(source, MAX_SVG_BYTES)
    if b"<!ENTITY" in data:
        raise StippleError(f"{name}: SVGs that declare entities are not read (nothing is expanded)")
    try:
        root = ElementTree.fromstring(data)
    except ElementTree.ParseError as error:
        raise StippleError(f"{name}: not a readable SVG ({error})") from None
    if _tag(root) != "svg":
        raise StippleError(f"{name}: not an SVG (the root element is <{_tag(root)}>)")
    try:
        with np.errstate(over="ignore", invalid="ignore"):  # what overflows is refused below, in one line
            layers = pen_layers(root)
    except (ValueError, IndexError) as error:
        raise StippleError(f"{name}: {error}") from None
    except OverflowError:
        raise StippleError(f"{name}: a shape's numbers are too large to draw") from None
    for layer in layers:
        for path in layer.paths:
            if not np.all(np.abs(path) <= MAX_COORDINATE_MM):  # NaN fails too
                raise StippleError(
                    f"{name}: layer {layer.name!r} has a vertex that is not a number or lies farther than "
                    f"{MAX_COORDINATE_MM:g} mm from the origin"
                )
    return layers


def pen_layers(root):
    """``PenLayer``s of a parsed ``<svg>`` element (see the module's docstring)."""
    base = _document_matrix(root) @ _transform(root.get("transform"))
    layers, loose = [], []
    for index, child in enumerate(root, start=1):
        tag = _tag(child)
        if tag in SKIPPED:
            continue
        if tag == "g":
            label = child.get(INKSCAPE_LABEL) or child.get("id") or str(index)
            layers.append(PenLayer(label, _shapes(child, base)))
        else:
            loose.extend(_shapes(child, base))
    if loose:
        layers.insert(0, PenLayer("(outside layers)", loose))
    return layers


def _tag(element):
    return element.tag.rpartition("}")[2] if isinstance(element.tag, str) else ""


def length_mm(text, default_unit=""):
    """Millimetres of an SVG length such as ``200mm``, ``8in`` or ``800`` (CSS pixels)."""
    match = re.fullmatch(rf"\s*({DECIMAL})\s*(mm|cm|in|px|pt|pc)?\s*", text or "")
    if not match:
        raise ValueError(f"cannot read the length {text!r} (a number with mm, cm, in, px, pt or pc)")
    return float(match.group(1)) * MM_PER[match.group(2) or default_unit]


def _document_matrix(root):
    """The 3x3 matrix from the root's user units to millimetres (``viewBox`` onto ``width`` × ``height``)."""
    view_box = root.get("viewBox")
    if view_box is None:
        return np.diag([MM_PER["px"], MM_PER["px"], 1.0])
    values = [float(value) for value in re.findall(DECIMAL, view_box)]
    if len(values) != 4:
        raise ValueError(f"cannot read the viewBox {view_box!r} (four numbers: x, y, width, height)")
    x0, y0, width, height = values
    if not (width > 0 and height > 0):
        raise ValueError(f"the viewBox {view_box!r} must have a positive width and height")
    sx = length_mm(root.get("width")) / width if root.get("width") else MM_PER["px"]
    sy = length_mm(root.get("height")) / height if root.get("height") else sx
    return np.array([[sx, 0, -sx * x0], [0, sy, -sy * y0], [0, 0, 1.0]])


def _transform(text):
    """The 3x3 matrix of an SVG ``transform`` attribute (identity when absent)."""
    matrix = np.eye(3)
    for name, arguments in re.findall(r"(matrix|translate|scale|rotate|skewX|skewY)\s*\(([^)]*)\)", text or ""):
        values = [float(value) for value in re.findall(DECIMAL, arguments)]
        if len(values) not in TRANSFORM_ARGUMENTS[name]:
            raise ValueError(f"cannot read the transform {name}({arguments.strip()})")
        matrix = matrix @ _one_transform(name, values)
    return matrix


# How many numbers each transform function takes (SVG 1.1, 7.6).
TRANSFORM_ARGUMENTS = {
    "matrix": (6,),
    "translate": (1, 2),
    "scale": (1, 2),
    "rotate": (1, 3),
    "skewX": (1,),
    "skewY": (1,),
}


def _one_transform(name, values):
    if name == "matrix":
        a, b, c, d, e, f = values
        return np.array([[a, c, e], [b, d, f], [0, 0, 1.0]])
    if name == "translate":
        x, y = (values + [0.0])[:2]
        return np.array([[1, 0, x], [0, 1, y], [0, 0, 1.0]])
    if name == "scale":
        x, y = (values + values)[:2]
        return np.diag([x, y, 1.0])
    if name == "rotate":
        angle, cx, cy = (values + [0.0, 0.0])[:3]
        cos, sin = np.cos(np.radians(angle)), np.sin(np.radians(angle))
        shift = np.array([[1, 0, cx], [0, 1, cy], [0, 0, 1.0]])
        back = np.array([[1, 0, -cx], [0, 1, -cy], [0, 0, 1.0]])
        return shift @ np.array([[cos, -sin, 0], [sin, cos, 0], [0, 0, 1.0]]) @ back
    skew = np.tan(np.radians(values[0]))
    return (
        np.array([[1, skew, 0], [0, 1, 0], [0, 0, 1.0]])
        if name == "skewX"
        else np.array([[1, 0, 0], [skew, 1, 0], [0, 0, 1.0]])
    )


def _apply(matrix, path):
    return (matrix[0, 0] * path.real + matrix[0, 1] * path.imag + matrix[0, 2]) + 1j * (
        matrix[1, 0] * path.real + matrix[1, 1] * path.imag + matrix[1, 2]
    )


def _shapes(element, matrix, depth=0):
    """The strokes of ``element`` and everything inside it, in document order, in millimetres."""
    tag = _tag(element)
    if tag in SKIPPED:
        return []
    if depth > MAX_GROUP_DEPTH:
        raise ValueError(f"groups are nested more than {MAX_GROUP_DEPTH} deep")
    matrix = matrix @ _transform(element.get("transform"))
    if tag in ("g", "a", "svg", "switch"):
        return [path for child in element for path in _shapes(child, matrix, depth + 1)]
    return [_apply(matrix, path) for path in _element_paths(tag, element) if len(path) >= 2]


def _number(element, name):
    value = element.get(name)
    if value is None:
        return 0.0
    numbers = re.findall(DECIMAL, value)
    if not numbers:
        raise ValueError(f"cannot read <{_tag(element)} {name}={value!r}> (a number)")
    return float(numbers[0])


def _lengths(element, *names):
    """The sizes ``names`` of a shape: a negative one is an error in SVG (drawn as a real circle before, a hostile
    sweep); a zero one draws nothing (the caller's check)."""
    values = [_number(element, name) for name in names]
    for name, value in zip(names, values, strict=True):
        if value < 0:
            raise ValueError(f"<{_tag(element)} {name}={element.get(name)!r}> is negative (an error in SVG)")
    return values


def _element_paths(tag, element):
    """User-unit strokes of one shape element (complex vertex arrays)."""
    if tag == "path":
        return path_strokes(element.get("d") or "")
    if tag in ("polyline", "polygon"):
        values = [float(value) for value in re.findall(DECIMAL, element.get("points") or "")]
        points = np.array(values[: len(values) // 2 * 2]).reshape(-1, 2) @ np.array([1.0, 1j])
        return [np.append(points, points[:1]) if tag == "polygon" and len(points) else points]
    if tag == "line":
        ends = [
            complex(_number(element, "x1"), _number(element, "y1")),
            complex(_number(element, "x2"), _number(element, "y2")),
        ]
        return [np.array(ends)]
    if tag == "rect":
        x, y = _number(element, "x"), _number(element, "y")
        w, h = _lengths(element, "width", "height")
        if w == 0 or h == 0:
            return []
        return [np.array([x + 1j * y, x + w + 1j * y, x + w + 1j * (y + h), x + 1j * (y + h), x + 1j * y])]
    if tag in ("circle", "ellipse"):
        cx, cy = _number(element, "cx"), _number(element, "cy")
        rx, ry = _lengths(element, "r") * 2 if tag == "circle" else _lengths(element, "rx", "ry")
        if rx == 0 or ry == 0:
            return []
        angles = np.linspace(0.0, 2 * np.pi, ROUND_SEGMENTS + 1)
        return [cx + rx * np.cos(angles) + 1j * (cy + ry * np.sin(angles))]
    return []
