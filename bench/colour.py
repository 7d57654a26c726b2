"""Colour stippling numbers: dots per ink against the channel masses, each ink's E_N against i.i.d. samples,
and the union's clump percentiles, for the joint objective and for the inks optimised apart (union weight 0).

    python bench/colour.py [--image /work/shared/data/astronaut.png] [--size 256] [-M 20000] [--iterations 400]
                           [--out out/colour] [--pictures docs]

Writes OUT/summary.json (and, with --pictures, the README's pictures of the joint run).
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np
from PIL import Image

from stipple.colour import halftone_colour
from stipple.measures.evaluate import discrepancy_energy, expected_iid_energy, torus_clumps
from stipple.pipelines.colour import ink_layers
from stipple.pipelines.outputs import layered_files


def load(path, size):
    image = Image.open(path).convert("RGB")
    scale = size / max(image.size)
    image = image.resize((round(image.width * scale), round(image.height * scale)), Image.LANCZOS)
    return np.asarray(image, dtype=np.float64) / 255.0


def measure(rgb, n_points, iterations, union_weight):
    started = time.perf_counter()
    layers, problem, result = halftone_colour(rgb, n_points, union_weight=union_weight, iterations=iterations)
    seconds = time.perf_counter() - started
    masses = np.array([layer.density.sum() for layer in layers])
    inks = []
    for layer, part, mass in zip(layers, problem.slices, masses, strict=True):
        subproblem = problem.classes[problem.names.index(layer.name)]
        points = result.points[part]
        inks.append(
            {
                "ink": layer.name,
                "mass_share": float(mass / masses.sum()),
                "quota": float(n_points * mass / masses.sum()),
                "dots": len(points),
                "bandwidth": subproblem.bandwidth,
                "energy_ratio_to_iid": discrepancy_energy(subproblem, points) / expected_iid_energy(subproblem),
                **torus_clumps(points, layer.density)["neighbour_distance_over_hexagonal"],
            }
        )
    union = sum(layer.density for layer in layers)
    return (
        layers,
        problem,
        result,
        {
            "union_weight": union_weight,
            "iterations": result.iterations,
            "seconds": seconds,
            "status": result.message,
            "inks": inks,
            "union": {
                "bandwidth": problem.bandwidth,
                "energy_ratio_to_iid": discrepancy_energy(problem, result.points) / expected_iid_energy(problem),
                **torus_clumps(result.points, union)["neighbour_distance_over_hexagonal"],
            },
        },
    )


def pictures(layers, problem, result, shape, directory):
    placed, ink = ink_layers(layers, problem, result)
    dots = layered_files(placed, shape, [".png"], {"png_width": 512}, ink=ink)[".png"]
    (directory / "colour-astronaut.png").write_bytes(dots)
    pen = {"png_width": 2048, "dot_style": "filled", "pen_width": (0.25, "mm")}
    preview = layered_files(placed, shape, [".png"], pen, ink=ink)[".png"]
    image = Image.open(__import__("io").BytesIO(preview))
    image.crop((820, 300, 1320, 700)).save(directory / "colour-plotter-filled.png", optimize=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--image", default="/work/shared/data/astronaut.png")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("-M", type=int, default=20000)
    parser.add_argument("--iterations", type=int, default=400)
    parser.add_argument("--out", default="out/colour")
    parser.add_argument("--pictures", default=None)
    args = parser.parse_args()
    rgb = load(args.image, args.size)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    summary = {"image": args.image, "shape": list(rgb.shape[:2]), "points": args.M, "runs": []}
    for union_weight in (1.0, 0.0):
        layers, problem, result, report = measure(rgb, args.M, args.iterations, union_weight)
        summary["runs"].append(report)
        print(json.dumps(report, indent=1), flush=True)
        if union_weight == 1.0 and args.pictures:
            pictures(layers, problem, result, rgb.shape[:2], Path(args.pictures))
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")


if __name__ == "__main__":
    main()
