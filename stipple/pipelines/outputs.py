"""A run's outputs: every format's bytes, points as CSV or GeoJSON and pictures from one ``Drawing``, made once
and serialised as SVG and PNG alike."""

from dataclasses import replace

import numpy as np

from ..errors import StippleError
from ..io.geojson import geojson_bytes
from ..io.points import csv_bytes, layered_csv_bytes
from ..io.writers import drawing_bytes
from ..render.flat import layered_drawing, line_drawing, torus_drawing
from ..render.globe import sphere_drawing

PICTURES = (".svg", ".png")


class OutputFiles(dict):
    """``{format: bytes}``, and the ``warnings`` of the drawing they hold (lines a user must see: dots left out)."""

    warnings = ()


def output_files(formats, points_bytes, drawing):
    """``OutputFiles`` for each of ``formats``: ``points_bytes(format)`` for CSV and GeoJSON, and SVG and PNG
    from the one ``drawing()``, made when the first of them is asked for."""
    made = []
    files = OutputFiles()
    for fmt in formats:
        if fmt in PICTURES:
            if not made:
                made.append(drawing())
                files.warnings = made[0].warnings
            files[fmt] = drawing_bytes(made[0], fmt)
        else:
            files[fmt] = points_bytes(fmt)
    return files


def pixel_columns(points, shape):
    """Unit coordinates of an image of ``shape = (H, W)`` in pixels."""
    rows, columns = shape
    return np.asarray(points) * np.array([columns, rows])


def flat_points(pixels, fmt):
    """CSV ``x,y`` of points in pixels; a flat canvas has no GeoJSON."""
    if fmt in (".geojson", ".json"):
        raise StippleError("GeoJSON output is for sphere points")
    return csv_bytes([pixels[:, 0], pixels[:, 1]], ["x", "y"])


def torus_files(points, shape, formats, settings, darkness=None):
    """Torus ``points`` (unit coordinates of an image of ``shape``): CSV ``x,y`` in pixels, and SVG and PNG drawn
    with ``settings`` (``stipple.render.flat.torus_drawing``) from the density ``darkness`` they were placed
    from."""
    return output_files(
        formats,
        lambda fmt: flat_points(pixel_columns(points, shape), fmt),
        lambda: torus_drawing(points, shape, darkness=darkness, **settings),
    )


def layered_files(layers, shape, formats, settings, numbers=None, **tone):
    """Layered torus dots, ``layers`` of ``(name, colour, points)``: CSV ``x,y,layer`` in pixels, SVG one Inkscape
    layer per ink (numbered ``numbers``, default 1, 2, ...), PNG the inks printed on the paper
    (``stipple.render.flat.layered_drawing``; ``tone``: ``ink``, ``coverages``, ``target``)."""

    def points_bytes(fmt):
        if fmt in (".geojson", ".json"):
            raise StippleError("GeoJSON output is for sphere points")
        pixels = np.concatenate([pixel_columns(points, shape) for _, _, points in layers])
        names = [name for name, _, points in layers for _ in range(len(points))]
        return layered_csv_bytes(pixels, names)

    def drawing():
        return replace(layered_drawing(layers, shape, **settings, **tone), layer_numbers=numbers)

    return output_files(formats, points_bytes, drawing)


def line_files(points, shape, formats, **settings):
    """A closed line's vertices (unit coordinates, path order): CSV ``x,y`` in pixels (the closing segment back to
    the first vertex implied), and SVG and PNG of the line (``stipple.render.flat.line_drawing``)."""
    return output_files(
        formats,
        lambda fmt: flat_points(pixel_columns(points, shape), fmt),
        lambda: line_drawing(points, shape, **settings),
    )


def sphere_files(points, lon_lat, formats, coords="lonlat", **settings):
    """Sphere ``points`` (unit vectors; ``lon_lat`` their degrees): CSV ``lon,lat`` or ``x,y,z`` in full
    precision, GeoJSON a MultiPoint, SVG and PNG the globe or the map (``stipple.render.globe.sphere_drawing``)."""

    def points_bytes(fmt):
        if fmt in (".geojson", ".json"):
            return geojson_bytes(np.stack(lon_lat, axis=1), {"points": len(points)})
        if coords == "xyz":
            return csv_bytes(list(points.T), ["x", "y", "z"], number_format=".17g")
        # Round-trip digits: 6 decimals of a degree would cap a spherical design's error near 6e-8.
        return csv_bytes(list(lon_lat), ["lon", "lat"], number_format=".17g")

    return output_files(formats, points_bytes, lambda: sphere_drawing(points, lon_lat, **settings))
