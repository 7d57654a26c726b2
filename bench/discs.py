"""Dot sizes optimised with the positions (``stipple.discs``) against sizes set after the fact (``stipple.tone``).

    python bench/discs.py [-M 3000 -M 10000 -M 30000] [--image PATH ...] [--threads 2] [--json OUT]

For each image and M:

* ``after``: what ``stipple torus`` draws by default: positions from ``stipple.halftone_torus`` (defaults), then
  each dot's radius set after the fact by ``stipple.render.dots.tone_dots`` (Voronoi-cell darkness, union-of-discs
  model, render-compare-correct passes, dots kept on the canvas);
* ``joint``: ``stipple.discs.optimise_discs`` from those positions (its defaults: every disc at the one tone
  radius, 200 CG iterations at most), positions and disc areas optimised together; drawn with its own radii;
* ``joint+tone``: the joint positions, radii set after the fact as in ``after`` (the disc model counts overlaps
  twice, the drawing does not; this is what a default could draw).

Each picture is the union of its discs (``stipple.tone.raster.union_coverage_image``, antialiased on the input
grid), luminance ``1 - coverage``, measured with ``stipple.measures.picture.measure_picture`` against ``1 - w`` at
sigma = 2 and 4 input pixels. Seconds: the halftone, the radii, the joint CG. Prints a markdown table.
"""

import argparse
import json
import os
import platform
import time

import stipple
from stipple.discs.problem import optimise_discs
from stipple.measures.picture import measure_picture
from stipple.render.dots import tone_dots
from stipple.tone.raster import union_coverage_image

HERE = os.path.dirname(os.path.abspath(__file__))
IMAGES = [os.path.join(HERE, "..", "samples", "astronaut256.png")]


def picture_error(weights, centres, radii):
    """RMSE at sigma 2 and 4 of the union of discs (pixel units) against the darkness ``weights``."""
    rows, columns = weights.shape
    coverage = union_coverage_image(centres, radii, (columns, rows), (rows, columns))
    measures = measure_picture(1.0 - weights, 1.0 - coverage, sigmas=(2.0, 4.0))
    return {f"rmse_sigma{m.sigma:g}": m.rmse for m in measures} | {"worst_tenth_sigma4": measures[1].worst_tenth}


def after_the_fact(weights, unit_points):
    """Radii set by the tone drawing for positions in unit coordinates: ``(centres, radii, seconds)`` in pixels."""
    rows, columns = weights.shape
    started = time.perf_counter()
    (dots,) = tone_dots([("ink", (0, 0, 0), unit_points * (columns, rows))], (columns, rows), [weights])
    return dots.centres, dots.radii, time.perf_counter() - started


def one_case(path, count, threads):
    weights = stipple.load_density(path)
    rows, columns = weights.shape
    started = time.perf_counter()
    halftone = stipple.halftone_torus(weights, count, threads=threads, seed=0)
    halftone_seconds = time.perf_counter() - started
    centres, radii, radii_seconds = after_the_fact(weights, halftone.points)
    rows_out = [
        {"variant": "after", "seconds": halftone_seconds + radii_seconds, "iterations": halftone.iterations}
        | picture_error(weights, centres, radii)
    ]
    joint = optimise_discs(weights, halftone.points, threads=threads)
    scale = max(rows, columns)
    rows_out.append(
        {"variant": "joint", "seconds": halftone_seconds + joint.seconds, "iterations": joint.iterations}
        | picture_error(weights, joint.points * (columns, rows), joint.radii * scale)
    )
    centres, radii, more = after_the_fact(weights, joint.points)
    rows_out.append(
        {"variant": "joint+tone", "seconds": halftone_seconds + joint.seconds + more, "iterations": joint.iterations}
        | picture_error(weights, centres, radii)
    )
    name = os.path.splitext(os.path.basename(path))[0]
    return [{"image": name, "M": count, "shape": [rows, columns]} | row for row in rows_out]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-M", "--count", type=int, action="append", help="dots (default 3000, 10000, 30000)")
    parser.add_argument("--image", action="append", help="input images (default the portrait)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--json", help="write the rows as JSON here")
    args = parser.parse_args()
    rows = []
    print("| image | M | variant | RMSE σ 4 | RMSE σ 2 | worst tenth σ 4 | seconds | iterations |")
    print("|---|---|---|---|---|---|---|---|")
    for path in args.image or IMAGES:
        for count in args.count or (3000, 10000, 30000):
            for row in one_case(path, count, args.threads):
                rows.append(row)
                print(
                    f"| {row['image']} | {row['M']} | {row['variant']} | {row['rmse_sigma4']:.4f} | "
                    f"{row['rmse_sigma2']:.4f} | {row['worst_tenth_sigma4']:.4f} | {row['seconds']:.1f} | "
                    f"{row['iterations']} |",
                    flush=True,
                )
    if args.json:
        meta = {"threads": args.threads, "python": platform.python_version(), "stipple": stipple.__version__}
        with open(args.json, "w") as handle:
            json.dump({"meta": meta, "rows": rows}, handle, indent=1)


if __name__ == "__main__":
    main()
