"""SVG path data (``d``) as pen strokes: one complex vertex array per subpath, curves and arcs flattened."""

import re

import numpy as np

from .units import DECIMAL

CURVE_SEGMENTS = 32
ARGUMENTS = {"M": 2, "L": 2, "H": 1, "V": 1, "Z": 0, "C": 6, "S": 4, "Q": 4, "T": 2, "A": 7}
# A command letter, a number, or anything else but separators (refused: "L nan 50" was read as L, an arc "a" and
# 50, and refused for L's count of numbers, a hostile sweep).
TOKEN = re.compile(rf"([MmLlHhVvZzCcSsQqTtAa])|({DECIMAL})|([^\s,]+)")


def path_strokes(data):
    """The strokes of SVG path data: every ``M`` (and every ``Z`` followed by a drawing command) starts a
    new one; ``C``/``S``/``Q``/``T`` curves get ``CURVE_SEGMENTS`` segments, arcs one per 1/256 turn.

    Raises
    ------
    ValueError
        On a number without a command before it or a command without enough numbers.
    """
    strokes, current, state = [], [], {"point": 0j, "start": 0j, "control": None, "last": ""}
    for command, values in _commands(data):
        relative = command.islower()
        upper = command.upper()
        origin = state["point"] if relative else 0j
        if upper == "M":
            if len(current) > 1:
                strokes.append(np.array(current))
            point = origin + complex(values[0], values[1])
            current, state["start"], state["point"] = [point], point, point
            state["control"], state["last"] = None, "M"
            continue
        if not current:
            current = [state["point"]]
        vertices = _segment(upper, values, origin, state, relative)
        current.extend(vertices)
        state["point"], state["last"] = current[-1], upper
        if upper == "Z":
            strokes.append(np.array(current))
            current = []
    if len(current) > 1:
        strokes.append(np.array(current))
    return strokes


def _commands(data):
    """``(command, numbers)`` pairs, implicit repetitions expanded (numbers after ``M`` are ``L``)."""
    command, numbers, pairs = None, [], []

    def flush():
        count = ARGUMENTS[command.upper()]
        if count == 0:
            if numbers:
                raise ValueError(f"path data: numbers after {command!r}")
            pairs.append((command, []))
            return
        if not numbers or len(numbers) % count:
            raise ValueError(f"path data: {command!r} needs a multiple of {count} numbers, not {len(numbers)}")
        for start in range(0, len(numbers), count):
            repeat = command if start == 0 or command.upper() != "M" else ("l" if command == "m" else "L")
            pairs.append((repeat, numbers[start : start + count]))

    for match in TOKEN.finditer(data):
        letter, number, other = match.groups()
        if other:
            near = data[max(match.start() - 12, 0) : match.end() + 12].strip()
            raise ValueError(f"path data: {other[:20]!r} is neither a command nor a number (in {near[:60]!r})")
        if letter:
            if command is not None:
                flush()
            command, numbers = letter, []
        elif command is None:
            raise ValueError("path data must start with a command (M)")
        else:
            numbers.append(float(number))
    if command is not None:
        flush()
    return pairs


def _segment(upper, values, origin, state, relative):
    """The vertices one drawing command adds after the current point (and the state's control point)."""
    point = state["point"]
    control = None
    if upper == "L":
        vertices = [origin + complex(values[0], values[1])]
    elif upper == "H":
        vertices = [complex((point.real if relative else 0.0) + values[0], point.imag)]
    elif upper == "V":
        vertices = [complex(point.real, (point.imag if relative else 0.0) + values[0])]
    elif upper == "Z":
        vertices = [state["start"]]
    elif upper in ("C", "S"):
        first = origin + complex(values[0], values[1]) if upper == "C" else _reflected(state, ("C", "S"))
        rest = [origin + complex(values[i], values[i + 1]) for i in range(0 if upper == "S" else 2, len(values), 2)]
        control = rest[-2]
        vertices = _bezier([point, first, *rest])
    elif upper in ("Q", "T"):
        control = origin + complex(values[0], values[1]) if upper == "Q" else _reflected(state, ("Q", "T"))
        end = origin + complex(values[-2], values[-1])
        vertices = _bezier([point, control, end])
    else:
        vertices = _arc(point, values, origin)
    state["control"] = control
    return vertices


def _reflected(state, kinds):
    """The reflection of the previous curve's last control point (S, T), or the current point."""
    if state["last"] in kinds and state["control"] is not None:
        return 2 * state["point"] - state["control"]
    return state["point"]


def _bezier(controls):
    """``CURVE_SEGMENTS`` vertices of the Bézier curve with these control points (the first one left out)."""
    t = np.linspace(0.0, 1.0, CURVE_SEGMENTS + 1)[1:]
    points = np.array(controls, dtype=complex)[:, None] * np.ones_like(t)
    while len(points) > 1:
        points = points[:-1] * (1 - t) + points[1:] * t
    return list(points[0])


def _arc(start, values, origin):
    """Vertices of an elliptical arc (SVG's endpoint form, implementation notes F.6) after ``start``."""
    rx, ry, rotation, large, sweep = abs(values[0]), abs(values[1]), np.radians(values[2]), values[3], values[4]
    end = origin + complex(values[5], values[6])
    if rx == 0 or ry == 0 or end == start:
        return [end]
    turn = np.exp(1j * rotation)
    half = (start - end) / 2 / turn
    scale = (half.real / rx) ** 2 + (half.imag / ry) ** 2
    if scale > 1:
        rx, ry = rx * np.sqrt(scale), ry * np.sqrt(scale)
    numerator = max(rx**2 * ry**2 - rx**2 * half.imag**2 - ry**2 * half.real**2, 0.0)
    factor = np.sqrt(numerator / (rx**2 * half.imag**2 + ry**2 * half.real**2))
    if bool(large) == bool(sweep):
        factor = -factor
    centre_local = factor * complex(rx * half.imag / ry, -ry * half.real / rx)
    centre = turn * centre_local + (start + end) / 2
    theta0 = np.angle(complex((half.real - centre_local.real) / rx, (half.imag - centre_local.imag) / ry))
    theta1 = np.angle(complex((-half.real - centre_local.real) / rx, (-half.imag - centre_local.imag) / ry))
    delta = (theta1 - theta0) % (2 * np.pi)
    if not sweep and delta > 0:
        delta -= 2 * np.pi
    steps = max(int(np.ceil(abs(delta) / (2 * np.pi) * 256)), 1)
    angles = theta0 + delta * np.linspace(0.0, 1.0, steps + 1)[1:]
    vertices = centre + turn * (rx * np.cos(angles) + 1j * ry * np.sin(angles))
    vertices[-1] = end
    return list(vertices)
