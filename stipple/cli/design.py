"""``stipple design``: numerical spherical designs of a given strength."""

import sys
import time

import click

from ..errors import StippleError
from ..render.styles import PROJECTIONS
from .options import (
    apply_options,
    config_option,
    init_input,
    output_options,
    render_settings,
    run_options,
    session_options,
    without,
)
from .supervise import finish, guarded_files, solve, write_outputs
from .values import Integer, Number, checked_count
from .views import check_view_drawn, parse_view

# The exit code of a run that ended without reaching --error (its points are written).
NOT_A_DESIGN = 3


def design_options(function):
    own = [
        config_option(),
        click.option(
            "-t", "--strength", type=Integer(), required=True, help="Degree t: integrate every harmonic of degree <= t."
        ),
        click.option(
            "-M",
            "--points",
            "n_points",
            type=Integer(),
            default=None,
            callback=checked_count,
            help="Number of points (default: ceil(0.55 (t+1)^2); (t+1)^2 converges in about 50 iterations).",
        ),
        click.option(
            "--error",
            type=Number(),
            default=1e-10,
            show_default=True,
            help="Stop when every harmonic's quadrature error is at most this.",
        ),
        click.option(
            "--init",
            default="auto",
            show_default=True,
            help="Start: 'lattice' (jittered Fibonacci), 'uniform' (i.i.d.), 'auto' (lattice from 0.65 (t+1)^2 "
            "points on; README), or a CSV of lon,lat or x,y,z.",
        ),
        click.option(
            "--coords", type=click.Choice(["lonlat", "xyz"]), default="xyz", show_default=True, help="CSV columns."
        ),
        click.option("--projection", type=click.Choice(PROJECTIONS), default="ortho", show_default=True),
        click.option(
            "--view",
            default="0,0",
            show_default=True,
            help="Centre LON,LAT of the globe view in degrees (equirect: the map's centre longitude).",
        ),
    ]
    return apply_options(function, own + run_options(iterations=20000) + output_options() + session_options())


@click.command()
# A design keeps its points' order, and its dots have no tone to keep (a uniform sphere).
@without("order", "style")
@design_options
@click.pass_context
def design(ctx, **options):
    """A numerical spherical design of strength t: M points whose equal-weight rule integrates every spherical
    harmonic of degree 1..t to within --error (CSV in full precision)."""
    from ..design import (
        DESIGN_EPSILON,
        GRADIENT_FLOOR,
        STARTS,
        ErrorTarget,
        accurate_check,
        design_outcome,
        design_problem,
        start_points,
    )
    from ..io.commit import output_format
    from ..pipelines.inputs import read_sphere_init
    from ..pipelines.outputs import sphere_files
    from ..sphere import lon_lat

    started = time.perf_counter()
    try:
        if not 0 < options["error"] < 1:
            raise StippleError(f"error must be a number in (0, 1), not {options['error']!r}")
        settings = render_settings(options)
        view = parse_view(options["view"], options["projection"])
        check_view_drawn(ctx, [output_format(path) for path in options["outputs"]])
        inputs = [init_input(options["init"], STARTS)]
        with guarded_files([i for i in inputs if i], options["outputs"], options["checkpoint"]):
            epsilon = DESIGN_EPSILON if options["epsilon"] is None else options["epsilon"]
            problem = design_problem(
                options["strength"], options["n_points"], threads=options["threads"], epsilon=epsilon
            )
            target = ErrorTarget(problem.discrepancy, options["error"])
            options.update(tol=GRADIENT_FLOOR, safeguard=False)
            init = options["init"] if options["init"] in STARTS else read_sphere_init(options["init"])
            init = start_points(options["strength"], problem.n_points, init, options["seed"])
            result, stopped_by = solve(problem, options, init, stop=target)
            accurate = accurate_check(options["strength"], problem.n_points, options["threads"], epsilon)
            result = design_outcome(result, target, accurate)
            files = sphere_files(
                result.points,
                lon_lat(result.points),
                [output_format(path) for path in options["outputs"]],
                coords=options["coords"],
                projection=options["projection"],
                view=view,
                ink=1.0,
                **settings,
            )
            write_outputs(options["outputs"], files, options["quiet"])
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)
    if result.status != "converged":
        # The points reached are written; a script must still be able to tell that they are not a design.
        if options["quiet"]:
            click.echo(f"stipple: {result.message}", err=True)
        sys.exit(NOT_A_DESIGN)
