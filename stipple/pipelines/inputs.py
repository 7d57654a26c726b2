"""The inputs of a run besides the image: saved points as torus or sphere points, ``--init`` starts, and the
canvas ``stipple render`` draws saved torus points on."""

import numpy as np

from ..errors import StippleError
from ..halftone import INITS, MAX_POINTS
from ..io.images import load_input
from ..io.points import parse_size, read_table
from ..sphere import from_lon_lat


def read_points(source, labels=False):
    """Points from a stipple CSV (``-`` is stdin): ``("torus", pixels)`` or ``("sphere", unit vectors)``.

    The header decides (``stipple.io.points.read_table``): ``x,y,z`` and ``lon,lat`` are sphere points, ``x,y``
    torus points in pixels. With ``labels``, also each torus point's layer, or None: ``(domain, points, names)``.
    """
    kind, points, *names = read_table(source, MAX_POINTS, labels)
    if kind == "lonlat":
        points = from_lon_lat(points[:, 0], points[:, 1])
    return ("torus" if kind == "xy" else "sphere", points, *names)


def read_torus_init(init, shape):
    """``stratified``/``density``/``uniform``, or a CSV ``x,y`` in pixel units converted to unit coordinates."""
    if init in INITS:
        return init
    domain, pixels = read_points(init)
    if domain != "torus":
        raise StippleError(f"{init}: --init for the torus needs a CSV with columns x,y (pixels)")
    rows, columns = shape
    return np.mod(pixels / np.array([columns, rows]), 1.0)


def read_sphere_init(init):
    """``density``/``uniform``, or a CSV of ``lon,lat`` degrees or ``x,y,z`` as unit vectors."""
    if init in INITS:
        return init
    domain, points = read_points(init)
    if domain != "sphere":
        raise StippleError(f"{init}: --init for the sphere needs a CSV with columns lon,lat or x,y,z")
    return points


def torus_canvas(pixels, like, size, transfer=None):
    """``(shape, darkness, pixels)`` of torus points: the canvas of ``--like`` (and its density, the tone to
    draw, with the run's ``transfer``: ``load_density``'s invert, gamma, levels, value_range) or ``--size`` (no
    density) with the points wrapped onto it, or by default the smallest canvas from the origin that holds every
    point."""
    if like is None and size is None:
        if len(pixels) and pixels.min() < 0:
            raise StippleError(
                f"{int((pixels < 0).any(axis=1).sum())} points lie left of or above the origin, off the canvas that "
                "starts there: give --like IMAGE or --size W,H to wrap them onto the image's canvas"
            )
        shape = (int(np.ceil(pixels[:, 1].max(initial=1))), int(np.ceil(pixels[:, 0].max(initial=1))))
        return (max(shape[0], 1), max(shape[1], 1)), None, pixels
    darkness = None
    if like is not None:
        darkness = load_input(like, **(transfer or {}))
        shape = darkness.shape
    else:
        shape = parse_size(size)
    return shape, darkness, np.mod(pixels, np.array([shape[1], shape[0]]))
