"""What ``stipple torus``, ``colour`` and ``batch`` ask of the pipelines: the recipe of one image from the options,
and the pipeline run under supervision (files guarded, progress, signals, summary), shared by the commands."""

import click

from ..errors import StippleError
from ..io.commit import FLAT_FORMATS, output_format
from .defaults import INITS
from .options import parse_levels, render_settings
from .supervise import (
    announcer,
    echo_notes,
    finish,
    guarded_files,
    report_run,
    run_keywords,
    supervised,
    write_outputs,
)


def torus_recipe(options):
    """What ``stipple torus`` does to an image with these options, as a ``stipple.pipelines.image.TorusRecipe``
    (the run's stopping, checkpoint and progress options are ``solve``'s)."""
    from ..pipelines.image import TorusRecipe

    return TorusRecipe(
        load={
            "invert": options["invert"],
            "gamma": options["gamma"],
            "value_range": options["value_range"],
            "levels": parse_levels(options["levels"]),
        },
        problem=problem_settings(options),
        solve={
            "init": options["init"],
            "seed": options["seed"],
            "tol": options["tol"],
            "iterations": options["iterations"],
            "time_limit": options["time_limit"],
            "safeguard": options["safeguard"],
            "beta": options["beta"],
            "correct": options["correct"],
            "settle": options["settle"],
        },
        draw=render_settings(options),
        order=options["order"] or False,
    )


def problem_settings(options):
    """The torus problem's settings of the options (``torus_problem``'s and ``colour_problem``'s keywords)."""
    from ..torus import DEFAULT_EPSILON

    return {
        "n_points": options["n_points"],
        "bandwidth": options["bandwidth"],
        "backend": options["backend"],
        "threads": options["threads"],
        "epsilon": DEFAULT_EPSILON if options["epsilon"] is None else options["epsilon"],
        "hessian": options["hessian"],
        "near_field": options["near_field"] is not False,
    }


def colour_recipe(options):
    """What ``stipple colour`` does to an image with these options, as a ``stipple.pipelines.colour.ColourRecipe``:
    options of the shared set that have no meaning for colour separation are refused, not ignored."""
    from ..colour import parse_palette
    from ..pipelines.colour import ColourRecipe

    check_colour_options(options)
    palette = parse_palette(options["palette"])
    draw = render_settings(options)
    draw.pop("color")
    return ColourRecipe(
        problem={
            **problem_settings(options),
            "separation": palette,
            "black": options["black"],
            "union_weight": options["union_weight"],
        },
        solve={"init": options["init"]},
        draw=draw,
        order=bool(options["order"]),
    )


def check_colour_options(options):
    """Refuse the options that colour separation would ignore."""
    if options.get("order") == "progressive":
        raise StippleError("--order progressive is for stipple torus with one ink; use --order here")
    if options["init"] not in INITS:
        raise StippleError(
            "--init must be stratified, density or uniform for colour separation (a start CSV is for one class); "
            "stratified starts from i.i.d. samples of each ink"
        )
    if options.get("invert") or options.get("value_range") is not None:
        raise StippleError("--invert and --range are for gray images and maps, not colour separation")
    if options.get("gamma", 1.0) != 1.0 or options.get("levels") is not None:
        raise StippleError("--gamma and --levels are for gray images and maps, not colour separation")
    if options.get("color") is not None or options.get("background") is not None:
        raise StippleError("--color and --background are for one-colour dots; colour separation prints on white paper")


def given_count_hint(darkness, options):
    """Notes on stderr for a given -M drawn in a pen or plotter style (``stipple.render.pen_count.given_count_notes``:
    tones its dots cannot reach, a point pen's dots too few for the image's ink); -M auto says its own."""
    if options["quiet"] or options["n_points"] == "auto":
        return
    from ..render.pen_count import given_count_notes

    echo_notes(given_count_notes(darkness, options["n_points"], render_settings(options), bool(options.get("invert"))))


def run_pipeline(pipeline, image, recipe, options, inputs, started, **observers):
    """``pipeline(image, formats, recipe, session=..., **observers)`` with the files guarded, the run supervised
    (its progress, checkpoint and signal keywords are the ``session``), the settings announced (``--verbose``),
    the pen-up travel reported, the outputs committed and the summary printed."""
    with guarded_files([i for i in inputs if i], options["outputs"], options["checkpoint"], formats=FLAT_FORMATS):
        formats = [output_format(path) for path in options["outputs"]]
        observers["announce"] = announcer(options)

        def launch(keywords):
            session = {**run_keywords(options), **keywords}
            return pipeline(image, formats, recipe, session=session, **observers)

        outputs, stopped_by = supervised(options, launch)
        report_run(outputs.result, options)
        if not options["quiet"]:
            echo_notes(outputs.notes)
        report_travel(outputs, options, recipe)
        write_outputs(options["outputs"], outputs.files, options["quiet"])
    finish(outputs.result, stopped_by, options, started)


def report_travel(outputs, options, recipe):
    """One line per ordered layer: the pen-up travel before and after ``--order``, and the passes of ``--order
    progressive`` (unless ``--quiet``)."""
    if options["quiet"]:
        return
    passes = getattr(outputs, "passes", None)
    suffix = f" in passes of {', '.join(str(count) for count in passes)} dots" if passes else ""
    unit = recipe.draw["width"][1]
    for before, after, ink in outputs.travel:
        layer = f" ({ink})" if ink else ""  # a colour run's three or four lines said which was which
        click.echo(f"stipple: pen-up travel{layer} {before:.4g} -> {after:.4g} {unit}{suffix}", err=True)
