"""``stipple sphere``: a map's points on the sphere (or, with --uniform, well-spread points and designs)."""

import time

import click

from ..errors import StippleError
from ..io.commit import output_format
from ..render.styles import PROJECTIONS
from .options import (
    click_error,
    common_options,
    init_input,
    is_default,
    render_settings,
    resolve_input,
)
from .supervise import finish, guarded_files, plot_order, solve, write_outputs
from .torus import peak_note
from .values import Number
from .views import check_longitude, check_view_drawn, parse_view


@click.command()
@click.argument("map_source", metavar="MAP", required=False)
@common_options
@click.option("--uniform", is_flag=True, help="w ≡ 1 (numerical spherical designs); no MAP.")
@click.option(
    "--lon0",
    type=Number(),
    default=0.0,
    show_default=True,
    help="Longitude (degrees east) where the map's first column starts (-180 for maps centred on 0°).",
)
@click.option(
    "--kernel",
    default=None,
    help="'distance' (the paper's; default for maps), 'distance+design:T' (default for --uniform: T = 0.96 sqrt(2M)) "
    "or 'sobolev:S'.",
)
@click.option(
    "--init",
    default="stratified",
    show_default=True,
    help="Start: 'stratified' (maps: coarse to fine from a start stratified over the map; otherwise as 'density'), "
    "'density' (i.i.d.), 'uniform', or a CSV of lon,lat (degrees) or x,y,z.",
)
@click.option(
    "--coords", type=click.Choice(["lonlat", "xyz"]), default="lonlat", show_default=True, help="CSV columns."
)
@click.option(
    "--projection",
    type=click.Choice(PROJECTIONS),
    default="ortho",
    show_default=True,
    help="PNG view: orthographic globe or equirectangular map.",
)
@click.option(
    "--view",
    default=None,
    help="Centre LON,LAT of the globe view in degrees (default 0,0); with --projection equirect the map's centre "
    "longitude (default: the input map's own layout, its first column at the left edge; 0 for --uniform and "
    "builtin maps).",
)
@click.pass_context
def sphere(ctx, map_source, **options):
    """Stipple MAP on the sphere: an equirectangular .npy map (rescaled to [0, 1]), an image (w = 1 - u),
    'builtin:gaussians' or 'builtin:rbf' (the paper's Figs. 5.4 and 5.5), or --uniform."""
    from ..io.png import check_png_outputs
    from ..pipelines.inputs import read_sphere_init
    from ..pipelines.outputs import sphere_files
    from ..pipelines.pen import sphere_pen_density
    from ..render.dots import sphere_canvas, sphere_png_layers
    from ..sphere import DESIGN_TOL, default_bandwidth, lon_lat, picture_darkness, sphere_density, sphere_problem
    from ..torus import DERIVATIVE_EPSILON

    started = time.perf_counter()
    map_source = resolve_input(ctx, map_source)
    try:
        settings = render_settings(options)
        lon0 = check_longitude("lon0", options["lon0"])
        layout = None if options["uniform"] or str(map_source).startswith("builtin:") else lon0
        view = parse_view(options["view"] or default_view(options["projection"], layout), options["projection"])
        formats = [output_format(path) for path in options["outputs"]]
        check_view_drawn(ctx, formats, names=("view",))
        projection = options["projection"]
        layers = sphere_png_layers(projection, (settings["color"], settings["background"]))
        check_png_outputs(formats, sphere_canvas(projection), options["png_width"], options["n_points"], layers)
        inputs = [("map", map_source), init_input(options["init"])]
        with guarded_files([i for i in inputs if i], options["outputs"], options["checkpoint"]):
            density = sphere_density(
                map_source,
                uniform=options["uniform"],
                invert=options["invert"],
                gamma=options["gamma"],
                value_range=options["value_range"],
                lon0=lon0,
            )
            warn_aspect(density, map_source, options)
            density = sphere_pen_density(density, options["n_points"], settings, options["projection"])
            if options["bandwidth"] is None:  # a narrow peak took minutes, without a word (a held-out review)
                even, peaked = default_bandwidth(options["n_points"]), default_bandwidth(options["n_points"], density)
                peak_note(even, peaked, options, "map's densest part", "a narrow peak, lights at night")
            problem = sphere_problem(
                density,
                options["n_points"],
                options["bandwidth"],
                kernel=options["kernel"],
                threads=options["threads"],
                epsilon=options["epsilon"],
                near_field=options["near_field"],
                derivative_epsilon=DERIVATIVE_EPSILON,
            )
            if problem.settings["kernel"].startswith("distance+design") and is_default(ctx, "tol"):
                options["tol"] = DESIGN_TOL
            result, stopped_by = solve(problem, options, read_sphere_init(options["init"]))
            points = plot_order(result.points, result.points, options, "radians")
            degrees = lon_lat(points)
            files = sphere_files(
                points,
                degrees,
                formats,
                coords=options["coords"],
                projection=options["projection"],
                view=view,
                ink=density.mean,
                darkness_at=picture_darkness(density),
                **settings,
            )
            write_outputs(options["outputs"], files, options["quiet"])
    except StippleError as error:
        raise click_error(error) from None
    finish(result, stopped_by, options, started)


# An equirectangular map spans 360 by 180 degrees: 2:1, to two columns or 2 % of them.
MAP_ASPECT_TOLERANCE = 0.02


def warn_aspect(density, source, options):
    """A note on stderr for a map that is not 2:1: it is read as 360 by 180 degrees all the same, so its pixels are
    stretched on the globe (a 3:1 panorama's features come out 1.5 times as tall)."""
    values = getattr(density, "values", None)
    if options["quiet"] or values is None:
        return
    rows, columns = values.shape
    if abs(columns - 2 * rows) > max(2, MAP_ASPECT_TOLERANCE * columns):
        click.echo(
            f"stipple: note: {source} is {columns}×{rows}, not 2:1; read as an equirectangular map of 360° by "
            "180°, so its features are stretched on the globe",
            err=True,
        )


def default_view(projection, lon0):
    """The view without ``--view``: the globe faces 0,0; the equirectangular map has the input map's layout (its
    first column, at longitude ``lon0``, at the left edge), so that the picture lies over the map. Without a map
    file (``lon0`` None: --uniform, a builtin map) the map is centred on 0° as ``stipple design`` and ``stipple
    render`` centre theirs."""
    return f"{lon0 + 180:g},0" if projection == "equirect" and lon0 is not None else "0,0"
