"""One-line drawing against TSP art: the same image, the same count, drawn 1 px wide, compared after blurring.

For each image: ``stipple.draw_line`` with M vertices, and ``stipple torus`` dots (M of them, CLI defaults) toured
by LKH-3 (``elkai``, an optional benchmark dependency: ``pip install elkai``). Both closed lines are drawn 1 px
wide at the image's resolution, blurred (sigma 2 and 4 px) and scaled by least squares onto the blurred density
(``stipple.measures.evaluate.fitted_similarity``). Prints one JSON object per image, with the line's share of vertices
within one stroke spacing of each edge against the image's share of darkness there.

    python bench/line_vs_tsp.py [IMAGE ...] [-M 20000] [--size 256] [--iterations 400] [--png DIR]
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np
from PIL import Image

from stipple.line import LINE_ITERATIONS, draw_line
from stipple.measures.evaluate import fitted_similarity, line_ink
from stipple.torus import halftone_torus

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_IMAGES = [ROOT / "samples/astronaut256.png", Path("/work/shared/data/camera.png")]
# LKH-3 settings for tens of thousands of cities: Delaunay candidates (the default alpha-nearness is quadratic)
# without the subgradient ascent, which took over 10 minutes for 30000 cities. Without it, 30000 uniform random
# cities in 512² got a tour of 0.719 sqrt(n A) in 3.4 s (the Beardwood-Halton-Hammersley constant is about 0.712).
LKH_PARAMETERS = (
    "RUNS = 1\nCANDIDATE_SET_TYPE = DELAUNAY\nINITIAL_TOUR_ALGORITHM = GREEDY\nSUBGRADIENT = NO\n"
    "MAX_CANDIDATES = 5\nMAX_TRIALS = {trials}\n"
)
LKH_SCALE = 1000.0  # EUC_2D rounds distances to integers: coordinates in 1/1000 pixel


def lkh_tour(pixels, trials=1):
    """A closed LKH-3 tour through ``pixels`` (vertex order)."""
    from elkai import _elkai

    lines = [f"TYPE : TSP\nDIMENSION : {len(pixels)}\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION"]
    lines += [f"{i + 1} {x * LKH_SCALE:.0f} {y * LKH_SCALE:.0f}" for i, (x, y) in enumerate(pixels)]
    params = LKH_PARAMETERS.format(trials=trials) + "PROBLEM_FILE = :stdin:\n"
    order = np.asarray(_elkai.solve_problem(params, "\n".join(lines) + "\n"), dtype=int) - 1
    return pixels[order]


def loop_length(pixels):
    return float(np.sum(np.linalg.norm(np.roll(pixels, -1, axis=0) - pixels, axis=1)))


def load(path, size):
    """The density of an image scaled to ``size`` pixels wide (``w = 1 - luminance``)."""
    image = Image.open(path).convert("L")
    if image.width != size:
        image = image.resize((size, round(image.height * size / image.width)), Image.Resampling.LANCZOS)
    return 1 - np.asarray(image, dtype=np.float64) / 255


def border_shares(weights, pixels, length):
    """Per edge: the share of the line's vertices within one stroke spacing ``W H / L`` of it, and the share of
    the image's darkness there (what a line that follows the darkness would put there)."""
    rows, columns = weights.shape
    band = weights.size / length
    width = int(np.ceil(band))
    x, y = pixels[:, 0], pixels[:, 1]
    total = weights.sum()
    shares = {
        "top": (np.mean(y < band), weights[:width].sum() / total),
        "bottom": (np.mean(y > rows - band), weights[-width:].sum() / total),
        "left": (np.mean(x < band), weights[:, :width].sum() / total),
        "right": (np.mean(x > columns - band), weights[:, -width:].sum() / total),
    }
    return {edge: [round(float(a), 4), round(float(b), 4)] for edge, (a, b) in shares.items()}


def compare(path, count, size, iterations, png_dir):
    weights = load(path, size)
    scale = np.array([weights.shape[1], weights.shape[0]])
    started = time.perf_counter()
    line = draw_line(weights, count, iterations=iterations)
    line_seconds = time.perf_counter() - started
    line_pixels = line.points * scale
    started = time.perf_counter()
    dots = halftone_torus(weights, count)
    dots_seconds = time.perf_counter() - started
    started = time.perf_counter()
    tour = lkh_tour(np.mod(dots.points, 1.0) * scale)
    tour_seconds = time.perf_counter() - started
    segments = np.linalg.norm(np.roll(line_pixels, -1, axis=0) - line_pixels, axis=1)
    report = {"image": str(path), "shape": list(weights.shape), "M": count}
    for name, pixels in (("line", line_pixels), ("tsp", tour)):
        ink = line_ink(pixels, weights.shape)
        report[name] = {
            "length_px": round(loop_length(pixels), 1),
            "psnr": {f"sigma{s['sigma']:g}": round(s["psnr"], 2) for s in fitted_similarity(weights, ink)},
        }
        if png_dir is not None:
            Image.fromarray(np.round(255 * (1 - ink)).astype(np.uint8)).save(Path(png_dir) / f"{path.stem}-{name}.png")
    report["line"].update(
        seconds=round(line_seconds, 1),
        iterations=int(line.iterations),
        penalty=line.problem.settings["penalty"],
        max_over_mean_segment=round(float(segments.max() / segments.mean()), 4),
        border_line_and_darkness_shares=border_shares(weights, line_pixels, loop_length(line_pixels)),
        min_over_mean_segment=round(float(segments.min() / segments.mean()), 4),
    )
    report["tsp"].update(dots_seconds=round(dots_seconds, 1), tour_seconds=round(tour_seconds, 1))
    report["gain_db"] = {
        key: round(report["line"]["psnr"][key] - report["tsp"]["psnr"][key], 2) for key in report["line"]["psnr"]
    }
    return report


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("images", nargs="*", type=Path, default=DEFAULT_IMAGES)
    parser.add_argument("-M", type=int, default=20000)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--iterations", type=int, default=LINE_ITERATIONS)
    parser.add_argument("--png", default=None, help="directory for the drawn lines (1 px, image resolution)")
    args = parser.parse_args()
    for path in args.images:
        print(json.dumps(compare(path, args.M, args.size, args.iterations, args.png)), flush=True)


if __name__ == "__main__":
    main()
