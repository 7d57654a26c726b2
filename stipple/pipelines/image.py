"""One image on the torus, as ``stipple torus`` and every image of ``stipple batch`` make it: the recipe, then
load -> problem -> solve -> order -> drawing -> each output's bytes."""

from dataclasses import dataclass, field

from ..errors import StippleError
from ..halftone import check_bandwidth, check_count, check_epsilon, check_run_options, check_threads, run
from ..io.images import check_load_options, load_input
from ..io.png import check_png_outputs
from ..nufft import BACKENDS
from ..torus import DERIVATIVE_EPSILON, torus_problem
from .inputs import read_torus_init
from .outputs import torus_files
from .pen import counted_recipe, order_kind, ordered_points, placement_density


@dataclass(frozen=True)
class TorusRecipe:
    """What ``stipple torus`` does to one image, as plain keyword dictionaries (picklable, for remote workers).

    Attributes
    ----------
    load : dict
        Keywords of ``stipple.io.images.load_input`` (invert, gamma, value_range, levels).
    problem : dict
        Keywords of ``stipple.torus.torus_problem`` after the weights: n_points (a number, or "auto": from the
        pen and the paper of ``draw``, ``stipple.render.pen_count``), bandwidth, backend, threads, epsilon,
        hessian, near_field.
    solve : dict
        Keywords of ``stipple.halftone.run`` (init as "stratified", "density" or "uniform", seed, tol, iterations,
        time_limit, safeguard, beta, correct, settle).
    draw : dict
        Keywords of ``stipple.render.flat.torus_drawing`` (width, dot_radius, png_width, background, color,
        dot_style, pen_width, style).
    order : bool or str
        Reorder the dots for a pen plotter: ``True`` or "path" along one short pen path (``--order``);
        "progressive" optimised as nested passes and drawn pass by pass (``stipple.progressive``).
    """

    load: dict = field(default_factory=dict)
    problem: dict = field(default_factory=dict)
    solve: dict = field(default_factory=dict)
    draw: dict = field(default_factory=dict)
    order: bool | str = False


@dataclass
class ImageOutputs:
    """One image's outputs: ``files`` maps a format (".csv", ".png", ".svg") to its bytes; ``result`` is the
    optimiser's ``HalftoneResult``; ``travel`` the pen-up travel ``(before, after, ink)`` of ``--order``, in the
    unit of the drawing's width, of each layer ordered (none without it; ``ink`` None for one ink);
    ``passes`` the dots per pass of ``--order progressive``; ``count`` the ``PenCount`` of ``-M auto``; ``notes``
    lines for the user about the outputs (an ink that got no dots)."""

    files: dict
    result: object
    travel: list = field(default_factory=list)
    passes: list = field(default_factory=list)
    count: object = None
    notes: list = field(default_factory=list)


def stipple_image(image, formats, recipe, *, session=None, inspect=None, announce=None, chosen=None):
    """Stipple ``image`` (a path) as ``stipple torus`` does and draw it in every format of ``formats``.

    Parameters
    ----------
    image : str
        Path of the image (PNG, JPEG, ..., or a .npy map).
    formats : iterable of str
        Output formats with their dot: ".csv", ".png", ".svg".
    recipe : TorusRecipe
    session : dict, optional
        Keywords of ``stipple.halftone.run`` that override ``recipe.solve``: the command line's progress and
        signal ``callback``, checkpoint and resume.
    inspect, announce : callable, optional
        Observers: ``inspect(weights)`` is shown the density once it is loaded, ``announce(problem)`` the problem
        before it runs (the command line's hints and ``--verbose``).
    chosen : callable, optional
        Observer of ``-M auto``: ``chosen(count)`` is shown the ``PenCount`` before the run.

    Returns
    -------
    ImageOutputs
    """
    formats = list(formats)
    weights = load_input(image, **recipe.load)
    if inspect is not None:
        inspect(weights)
    recipe, count = counted_recipe(recipe, weights)
    if count is not None and chosen is not None:
        chosen(count)
    placed = placement_density(weights, recipe.problem["n_points"], recipe.draw)
    problem = image_problem(placed, formats, recipe)
    options = {**recipe.solve, **(session or {})}
    init = read_torus_init(options.pop("init", "stratified"), weights.shape)
    if announce is not None:
        announce(problem)
    result = run(problem, init=init, **options)
    points, travel, passes = ordered_points(result.points, problem, weights.shape, recipe)
    files = torus_files(points, weights.shape, formats, recipe.draw, placed)
    return ImageOutputs(files, result, travel, passes, count)


def image_problem(weights, formats, recipe):
    """The torus problem of the density ``weights`` with ``recipe.problem``'s settings, once the PNG canvas that
    ``formats`` need is known to fit in memory; with ``--order progressive`` the nested levels' problem
    (``stipple.progressive.progressive_problem``). The plain problem's derivatives are single-precision
    transforms (``stipple.torus.DERIVATIVE_EPSILON``)."""
    settings = dict(recipe.problem)
    n_points = settings.pop("n_points")
    check_png_outputs(formats, weights.shape[::-1], recipe.draw.get("png_width"), n_points)
    if order_kind(recipe.order) == "progressive":
        from ..progressive import progressive_problem

        return progressive_problem(weights, n_points, settings.pop("bandwidth", None), **settings)
    bandwidth = settings.pop("bandwidth", None)
    return torus_problem(weights, n_points, bandwidth, derivative_epsilon=DERIVATIVE_EPSILON, **settings)


def check_recipe(recipe):
    """Raise if a setting of ``recipe`` is out of range, as its run would, before any image is read (so that a
    batch refuses a bad option once, before any work)."""
    check_load_options(**recipe.load)
    problem = recipe.problem
    check_count(problem.get("n_points"))
    if problem.get("bandwidth") is not None:
        check_bandwidth(problem["bandwidth"])
    if problem.get("threads") is not None:
        check_threads(problem["threads"])
    if "epsilon" in problem:
        check_epsilon(problem["epsilon"])
    if problem.get("backend", BACKENDS[0]) not in BACKENDS:
        raise StippleError(f"backend must be one of {', '.join(BACKENDS)}, not {problem['backend']!r}")
    check_run_options(**recipe.solve)
