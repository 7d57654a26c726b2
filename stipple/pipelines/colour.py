"""A colour image with one layer of dots per ink, as ``stipple colour`` (and ``stipple torus --palette``) make it:
separation -> joint problem -> solve -> each ink's dots, ordered per pen -> layered drawing -> outputs."""

from dataclasses import dataclass, field

import numpy as np

from ..colour import (
    INK_COLOURS,
    check_layer_names,
    colour_problem,
    palette_inks,
    palette_number,
    print_target,
    separate,
)
from ..halftone import run
from ..io.images import load_colour
from ..io.png import check_png_outputs
from ..io.units import parse_colour
from ..render.pen import pen_order, physical_centres
from .image import ImageOutputs
from .outputs import layered_files
from .pen import placement_density

# Canvas-sized images alive at once while the inks' picture is drawn (about 33 bytes a pixel).
INK_PICTURE_LAYERS = 33


@dataclass(frozen=True)
class ColourRecipe:
    """What ``stipple colour`` does to one image.

    Attributes
    ----------
    problem : dict
        Keywords of ``stipple.colour.colour_problem`` after the image: n_points, bandwidth, separation (a parsed
        palette), black, union_weight, backend, threads, epsilon, hessian, near_field.
    solve : dict
        Keywords of ``stipple.halftone.run`` (init, seed, tol, ...).
    draw : dict
        Keywords of ``stipple.render.flat.layered_drawing`` (width, dot_radius, png_width, background,
        dot_style, pen_width, style).
    order : bool
        Reorder each ink's dots along a short pen path (each pen draws its own layer).
    """

    problem: dict = field(default_factory=dict)
    solve: dict = field(default_factory=dict)
    draw: dict = field(default_factory=dict)
    order: bool = False


def ink_layers(layers, problem, result):
    """``(name, colour, points)`` per ink (``points`` in unit coordinates, ``result.points[problem.slices[c]]``),
    and the union's mean density: the ink that all the dots together lay down."""
    placed = [
        (layer.name, layer.colour, result.points[part]) for layer, part in zip(layers, problem.slices, strict=True)
    ]
    return placed, union_ink([layer.density for layer in layers])


def union_ink(densities):
    """The mean density of all the inks' ``densities`` together: the ink that all the dots lay down."""
    return float(sum(densities).mean())


def tone_settings(densities, rgb, separation):
    """The tone style's keywords of ``layered_files`` for the inks' ``densities`` (in the drawing's layer order) of
    ``rgb`` separated by ``separation`` (``stipple colour``, its redraw and a colour video's frames): each ink's
    coverage, the colour they print and their mean ink."""
    coverages = [np.clip(density, 0.0, 1.0) for density in densities]
    return {"coverages": coverages, "target": print_target(rgb, separation), "ink": union_ink(densities)}


def stipple_colour(image, formats, recipe, *, session=None, inspect=None, announce=None):
    """Separate ``image`` (a path) into inks, optimise their dots jointly and draw them in every format of
    ``formats``; ``session`` and ``announce`` as for ``stipple.pipelines.image.stipple_image``, ``inspect``
    is shown the inks' darkness together (H, W) once they are separated (before a pen's clip).

    Returns
    -------
    ImageOutputs
        ``travel`` holds each ordered ink's pen-up travel before and after.
    """
    formats = list(formats)
    rgb = load_colour(image)
    settings = dict(recipe.problem)
    n_points = settings.pop("n_points")
    check_png_outputs(formats, rgb.shape[1::-1], recipe.draw["png_width"], n_points, layers=INK_PICTURE_LAYERS)

    def placement(union):
        # The inks' darkness together as separated, before a pen's clip: what the notes on the image speak of.
        if inspect is not None:
            inspect(np.clip(union, 0.0, 1.0))
        return placement_density(union, n_points, recipe.draw)

    layers, problem = colour_problem(rgb, n_points, settings.pop("bandwidth"), placement=placement, **settings)
    if announce is not None:
        announce(problem)
    result = run(problem, **{**recipe.solve, **(session or {})})
    placed, _ = ink_layers(layers, problem, result)
    shape, travel = rgb.shape[:2], []
    if recipe.order:
        placed, travel = ordered_layers(placed, shape, recipe.draw["width"])
    tone = tone_settings([layer.density for layer in layers], rgb, settings["separation"])
    inks = palette_inks(settings["separation"])
    numbers = [palette_number(settings["separation"], name) for name, _, _ in placed]
    files = layered_files(placed, shape, formats, recipe.draw, numbers, **tone)
    return ImageOutputs(files, result, travel, notes=missing_inks(inks, [name for name, _, _ in placed]))


def missing_inks(inks, placed):
    """A line naming the palette's ``inks`` that got no dots (none where every ink is ``placed``): their SVG
    layers' numbers are left free, so that every pen keeps its slot (a held-out review: an empty cyan made magenta
    layer 1)."""
    missing = [name for name in inks if name not in placed]
    if not missing:
        return []
    return [
        f"no dots for {', '.join(missing)} (too little of the image's ink for one dot); the SVG's layers keep "
        "their palette numbers"
    ]


def ordered_layers(placed, shape, width):
    """Each layer's points along a short pen path of its own (layers of fewer than 2 dots as they are), and the
    pen-up travel before and after of each layer ordered, with its name."""
    ordered, travel = [], []
    for name, colour, points in placed:
        if len(points) >= 2:
            points, before, after = pen_order(points, physical_centres(points, shape, width))
            travel.append((before, after, name))
        ordered.append((name, colour, points))
    return ordered, travel


def redraw_layers(pixels, names, formats, draw, *, like=None, shape=None, palette=None, black=1.0, order=False):
    """Saved layered dots drawn again (``stipple render`` of a ``stipple colour`` CSV): ``pixels`` ``(M, 2)`` and
    each dot's layer name, each layer in its ink's colour (``cyan`` ... ``black``, or a pen named by its colour).

    With ``like``, the colour image the dots were made from (a path or its ``(H, W, 3)`` colours), the canvas is
    its own and the dots are drawn tone-true to its separation into ``palette`` (default: the inks the names are,
    ``layer_palette``); without it, on ``shape = (H, W)`` in the plotter style. ``order`` sorts each layer along
    a short pen path.
    """
    inks = list(dict.fromkeys(names.tolist()))
    palette = layer_palette(inks) if palette is None else palette
    tone = {}
    if like is not None:
        rgb = like if isinstance(like, np.ndarray) else load_colour(like)
        shape = rgb.shape[:2]
        separated = separate(rgb, palette, black)
        check_layer_names(inks, separated, palette)
        layers = {layer.name: layer for layer in separated}
        tone = tone_settings([layers[name].density for name in inks], rgb, palette)
    check_png_outputs(formats, shape[::-1], draw["png_width"], len(pixels), layers=INK_PICTURE_LAYERS)
    rows, columns = shape
    unit = np.mod(np.asarray(pixels) / np.array([columns, rows]), 1.0)
    placed = [(name, ink_colour(name), unit[names == name]) for name in inks]
    if order:
        placed, _ = ordered_layers(placed, shape, draw["width"])
    return layered_files(placed, shape, formats, draw, **tone)


def layer_palette(names):
    """The palette that layer ``names`` come from: "gray" for black alone, "cmy" for the colour inks without black
    (a cmyk separation with no black ink gives the same three), "cmyk" for inks of it, else pens named by their
    colours in the order given."""
    if set(names) == {"black"}:
        return "gray"
    if set(names) <= set(INK_COLOURS) - {"black"}:
        return "cmy"
    if set(names) <= set(INK_COLOURS):
        return "cmyk"
    return [(name, ink_colour(name)) for name in names]


def ink_colour(name):
    """An ink's colour (RGB in [0, 1]) by its name: a process ink, or a pen's colour as written."""
    return INK_COLOURS.get(name) or parse_colour(name, f"layer {name!r}: a layer name")
