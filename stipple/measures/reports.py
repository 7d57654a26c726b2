"""Evaluation reports (``stipple evaluate``): which measures of ``stipple.measures.evaluate`` apply to which kind
of point file (torus dots, sphere points, layered inks, one line); a drawn picture's measures
(``stipple.measures.picture``); and the reports' text form."""

import io

import numpy as np

from ..colour import check_layer_names, parse_palette, separate
from ..errors import MissingInput, StippleError
from ..io.images import NPY_MAGIC, given_transfer, load_colour, load_density, load_input
from ..io.sources import STDIN_NAME, read_source, source_or_stdin
from ..line.problem import length_bounds, line_problem
from ..multiclass import class_bandwidth
from ..render.pen import closed_length
from ..sphere import sphere_density, sphere_problem
from ..torus import torus_problem
from .evaluate import evaluate_line, evaluate_sphere, evaluate_torus
from .picture import SIGMAS, floyd_steinberg, mean_chroma, measure_picture

# Mean CIELAB chroma above which an input is measured in colour: a gray JPEG's noise stays well below it.
GRAY_CHROMA = 2.0
# The torus problems that measure points: transforms to 1e-10 at the full default bandwidth; measuring needs no
# metric, so the density-scaled one's stiffness field is not made.
MEASURE_OPTIONS = {"epsilon": 1e-10, "bandwidth_factor": 1.0, "precondition": False}
# ... and the sphere's: transforms to 1e-12 at the full default degree, the plain metric.
SPHERE_MEASURE_OPTIONS = {"epsilon": 1e-12, "bandwidth_factor": 1.0, "precondition": False}


def evaluation_report(
    domain, points, names, input_source, *, bandwidth=None, kernel="distance", as_line=False, **options
):
    """The report of ``points`` read from a CSV (``domain`` "torus" pixels or "sphere" unit vectors; ``names``
    each torus point's layer, or None) against ``input_source``.

    ``options`` are the density's transfer as for the run (``invert``, ``gamma``, ``value_range``; sphere:
    ``uniform``, ``lon0``; layered: ``palette``, ``black``).
    """
    if as_line:
        return evaluate_line_points(points, domain, input_source, bandwidth, options)
    if names is not None:
        return evaluate_layers(points, names, input_source, bandwidth, options)
    return evaluate_points(domain, points, input_source, bandwidth, kernel, options)


def evaluate_line_points(pixels, domain, input_source, bandwidth, options):
    """The report of ``stipple evaluate --line``: E_N of the vertices, length, segments, the drawn line's PSNR."""
    if input_source is None:
        raise MissingInput("missing INPUT: --line measures the vertices against the image they were drawn from")
    if domain != "torus":
        raise StippleError("--line needs a CSV of x,y vertices and the image they were drawn from")
    weights = load_input(input_source, **image_transfer(options))
    length = closed_length(pixels)
    if not length > 0:
        raise StippleError("the line has length 0: all its vertices are at one place")
    # The length sets only the measuring torus's blank margin and its bandwidth: any line is measured, a short or a
    # long one on the torus of the nearest length that ``stipple line`` allows.
    length = float(np.clip(length, *length_bounds(weights.shape)))
    # One node per segment: the measure is the vertices' own (with the run's nodes, the vertices carried 1 / K
    # of the image's mass, and the i.i.d. expectation came out negative: a hostile sweep).
    problem = line_problem(weights, len(pixels), length, bandwidth, epsilon=1e-10, subdivisions=1)
    return evaluate_line(problem, pixels / np.array([weights.shape[1], weights.shape[0]]), weights)


def evaluate_points(domain, points, input_source, bandwidth, kernel, options):
    """The evaluation report of torus pixels or sphere unit vectors against their input."""
    if domain == "torus":
        if input_source is None:
            raise MissingInput("missing INPUT: the image or map the points were made from")
        if str(input_source).startswith("builtin:"):  # it said "cannot read builtin:...: No such file"
            raise StippleError(
                f"{input_source}: the built-in densities are the sphere's; these are x,y points of an image (give "
                "the image or map they were made from)"
            )
        weights = load_input(input_source, **image_transfer(options))
        unit = np.mod(points / np.array([weights.shape[1], weights.shape[0]]), 1.0)
        problem = torus_problem(weights, len(points), bandwidth, **MEASURE_OPTIONS)
        return {**evaluate_torus(problem, unit, weights), **outside(points, weights.shape)}
    if input_source is None and not options["uniform"]:
        raise MissingInput("missing INPUT: the map the points were made from, builtin:NAME or --uniform")
    density = sphere_density(
        input_source,
        uniform=options["uniform"],
        invert=options["invert"],
        gamma=options["gamma"],
        value_range=options["value_range"],
        lon0=options["lon0"],
    )
    problem = sphere_problem(density, len(points), bandwidth, kernel=kernel, **SPHERE_MEASURE_OPTIONS)
    return evaluate_sphere(problem, points, density)


def image_transfer(options):
    """``load_density``'s keywords for the image the torus points were made from, as for the run."""
    keys = ("invert", "gamma", "value_range", "levels")
    return {key: options[key] for key in keys if options.get(key) is not None}


def outside(pixels, shape):
    """``{"points_outside": count, "image_size": [W, H]}``: how many pixel positions lie outside the image (points
    made for another image, whose positions the torus would wrap silently)."""
    rows, columns = shape[:2]
    pixels = np.asarray(pixels, dtype=np.float64)
    beyond = (pixels < 0).any(axis=1) | (pixels[:, 0] > columns) | (pixels[:, 1] > rows)
    return {"points_outside": int(beyond.sum()), "image_size": [int(columns), int(rows)]}


def evaluate_layers(pixels, names, input_source, bandwidth, options):
    """The report of all dots against the inks' summed density, with ``classes``: each ink's dots against its
    own density (its count beside its quota ``M · mass share``)."""
    if input_source is None:
        raise MissingInput("missing INPUT: the colour image the layered points were made from")
    rgb = load_colour(input_source)
    separation = parse_palette(options["palette"])
    layers = separate(rgb, separation, options["black"])
    check_layer_names(names.tolist(), layers, separation, input_source)
    rows, columns = rgb.shape[:2]
    unit = np.mod(pixels / np.array([columns, rows]), 1.0)
    union = sum(layer.density for layer in layers)
    report = evaluate_torus(torus_problem(union, len(unit), bandwidth, **MEASURE_OPTIONS), unit, union)
    report.update(outside(pixels, rgb.shape))
    report["classes"] = []
    for layer in layers:
        chosen = names == layer.name
        count, share = int(chosen.sum()), float(layer.density.sum() / union.sum())
        entry = {"name": layer.name, "points": count, "mass_share": share, "quota": share * len(unit)}
        if count >= 2:
            band = None if bandwidth is None else class_bandwidth(bandwidth, count, len(unit))
            problem = torus_problem(layer.density, count, band, **MEASURE_OPTIONS)
            measured = evaluate_torus(problem, unit[chosen], layer.density)
            entry.update({key: measured[key] for key in ("bandwidth", "energy", "energy_ratio_to_iid")})
            entry["neighbour_distance_over_hexagonal"] = measured.get("neighbour_distance_over_hexagonal")
        report["classes"].append(entry)
    return report


def format_report(report):
    """The evaluation as aligned ``name: value`` lines (the spectrum only as its range)."""
    lines = [
        f"domain: {report['domain']}",
        f"points: {report['points']}",
        f"bandwidth: {report['bandwidth']}",
        f"E_N: {report['energy']:.6e}",
        f"E_N of i.i.d. samples (expected): {report['expected_iid_energy']:.6e}",
        f"ratio to i.i.d.: {report['energy_ratio_to_iid']:.4g}",
        f"untruncated energy (with the near field): {report['untruncated_energy']:.6e}",
    ]
    for item in report.get("similarity", []):
        binned = f" (dots binned into pixels first: PSNR {item['psnr_binned']:.2f} dB)" if "psnr_binned" in item else ""
        lines.append(f"blur sigma {item['sigma']:g} px: PSNR {item['psnr']:.2f} dB, SSIM {item['ssim']:.4f}{binned}")
    if "neighbour_distance_over_hexagonal" in report:
        stats = report["neighbour_distance_over_hexagonal"]
        judged = ", ".join(f"{k} {v:.3f}" for k, v in stats.items()) or "no point lies where the input has ink"
        lines.append("nearest neighbour / hexagonal spacing: " + judged)
    for key in ("length_pixels", "max_over_mean_segment", "min_over_mean_segment"):
        if key in report:
            lines.append(f"{key.replace('_', ' ')}: {report[key]:.6g}")
    for key in ("max_coefficient_error", "minimum_separation_degrees", "cap_discrepancy"):
        if key in report:
            lines.append(f"{key.replace('_', ' ')}: {report[key]:.6g}")
    for item in report.get("classes", []):
        line = f"ink {item['name']}: {item['points']} dots (quota {item['quota']:.2f})"
        if "energy_ratio_to_iid" in item:
            line += f", N {item['bandwidth']}, ratio to i.i.d. {item['energy_ratio_to_iid']:.4g}"
        stats = item.get("neighbour_distance_over_hexagonal") or {}
        if stats:
            line += ", NN / hexagonal " + ", ".join(f"{k} {v:.3f}" for k, v in stats.items())
        lines.append(line)
    return "\n".join(lines)


def _check_sigmas(sigmas, shape):
    """Each blur ``sigma`` in (0, the picture's longer side] input pixels (a wider blur measures nothing and its
    kernel would outgrow memory)."""
    for sigma in sigmas:
        if not (np.isfinite(sigma) and 0 < sigma <= max(shape)):
            raise StippleError(
                f"sigma must be in (0, {max(shape)}] input pixels (the input's longer side), not {sigma:g}"
            )


def picture_report(picture_source, input_source, *, colour=None, sigmas=SIGMAS, inset=0.0, dots=None, **options):
    """The picture measures (``stipple.measures.picture``) of a drawn PNG against the input it was drawn from.

    ``colour``: CIELAB measures (True), luminance measures (False) or, None, colour exactly when the input is an
    image with chroma (mean C*ab above ``GRAY_CHROMA``). ``options`` are the density's transfer as for the run
    (``invert``, ``gamma``, ``levels``, ``value_range``): the gray reference is the tone the run was asked to draw,
    ``1 - w`` (``w`` with ``invert``: white dots on black). ``dots``: also measure Floyd-Steinberg error
    diffusion with about that many dots.
    """
    if str(input_source).startswith("builtin:"):
        raise StippleError(
            f"{input_source}: a picture is measured against the image or map file it was drawn from, not a built-in "
            "density (its points are: stipple evaluate POINTS.csv builtin:NAME)"
        )
    drawn = load_colour(picture_source, name=str(picture_source))
    data = read_source(source_or_stdin(input_source))
    name = STDIN_NAME if input_source == "-" else str(input_source)
    if colour is None:
        colour = not data.startswith(NPY_MAGIC) and mean_chroma(load_colour(io.BytesIO(data), name)) > GRAY_CHROMA
    if colour:
        given = given_transfer(options)
        if given:
            raise StippleError(
                f"{', '.join(given)}: for gray measures; a colour picture is measured against the image's colours "
                "(give --gray for its luminance)"
            )
        reference = load_colour(io.BytesIO(data), name)
    else:
        density = load_density(io.BytesIO(data), name=name, **options)
        reference = density if options.get("invert") else 1.0 - density
    _check_aspect(drawn.shape, reference.shape, picture_source, input_source)
    _check_sigmas(sigmas, reference.shape[:2])
    report = {
        "picture": str(picture_source),
        "input": name,
        "measures": "colour" if colour else "gray",
        "shape": list(reference.shape[:2]),
        "drawn_shape": list(drawn.shape[:2]),
        "inset": inset,
        "stipple": [m.as_dict() for m in measure_picture(reference, drawn, sigmas=sigmas, inset=inset)],
    }
    if dots is not None:
        baseline, inked = floyd_steinberg(reference, dots, light_dots=bool(options.get("invert")))
        report["floyd_steinberg"] = {
            "dots": inked,
            "measures": [m.as_dict() for m in measure_picture(reference, baseline, sigmas=sigmas)],
        }
    return report


def _check_aspect(drawn, reference, picture_source, input_source):
    """A picture is not a drawing of its input if its width : height differs from the input's by over 2 %, and
    is not what the rounding of its height to whole pixels makes (a PNG of stipple's is ``round(W h / w)`` rows
    high: a 1000×20 strip drawn 1024 wide is 1024×20, 2.4 % off)."""
    (rows, columns), (height, width) = drawn[:2], reference[:2]
    rounded = rows == max(int(round(columns * height / width)), 1)  # as ``stipple.io.png.png_canvas`` rounds
    if abs(np.log((columns / rows) / (width / height))) > 0.02 and not rounded:
        # A held-out review measured stipple sphere's default PNG, a globe, against its map and was told no more.
        globe = rows == columns and width == 2 * height
        hint = " (a globe is not measured: draw the points with --projection equirect)" if globe else ""
        raise StippleError(
            f"{picture_source} is {columns}x{rows} pixels but {input_source} is {width}x{height}: "
            f"not the same width : height, so not a drawing of it{hint}"
        )


def format_picture_report(report):
    """The picture measures as text: a line per blur (and the tone curve), then the Floyd-Steinberg baseline."""
    rows, columns = report["drawn_shape"]
    height, width = report["shape"]
    lines = [
        f"picture: {report['picture']} ({columns}x{rows}) against {report['input']} ({width}x{height}), "
        f"{report['measures']} measures, blurred on the input's pixels"
    ]
    lines += _picture_lines("stipple", report["stipple"])
    if "floyd_steinberg" in report:
        lines += _picture_lines(
            f"Floyd-Steinberg, {report['floyd_steinberg']['dots']} dots", report["floyd_steinberg"]["measures"]
        )
    return "\n".join(lines)


def _chroma_text(ratio):
    return "the input is neutral" if ratio is None else f"chroma {ratio:.3f} of the input's"


def _picture_lines(name, measures):
    for row in measures:
        if "delta_e00" in row:
            yield (
                f"{name}, sigma {row['sigma']:g} px: CIEDE2000 {row['delta_e00']:.2f} (95th percentile "
                f"{row['delta_e00_p95']:.2f}), {_chroma_text(row['chroma_ratio'])}, "
                f"mean L* difference {row['mean_L_difference']:+.2f}, luminance RMSE {row['luminance_rmse']:.4f}"
            )
            continue
        yield (
            f"{name}, sigma {row['sigma']:g} px: luminance RMSE {row['rmse']:.4f}, mean difference "
            f"{row['mean_difference']:+.4f}, worst tenth {row['worst_tenth']:.4f}"
        )
        curve = "  ".join(f"{b['input']:.2f}->{b['output']:.2f}" for b in row["tone_curve"])
        yield f"  tone curve (input -> drawn, per tenth): {curve}"
