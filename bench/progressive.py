"""``--order progressive`` against independent stipples: every prefix's E_N and picture, and the pen-up travel.

For each image and M, runs ``stipple torus IMAGE -M M --order progressive -o prog.csv`` (dots in plotting
order), ``stipple torus IMAGE -M M --order -o path.csv`` (one short path: the independent stipple of M dots) and
independent stipples of M/4, M/2 and 3M/4 dots. For the first 25 %, 50 %, 75 % and 100 % of the progressive
dots (the issue's bar is on 25, 50 and 100 %; 75 % is the end of the third pass) and for the
independent stipple of that many dots: E_N over its i.i.d. expectation (``stipple evaluate POINTS IMAGE``) and
the luminance RMSE at sigma 2 px of the tone-true picture (``stipple render --like IMAGE`` then ``stipple evaluate
PICTURE IMAGE``); and the pen-up travel of both orders from the commands' own lines. Writes
``out/progressive/summary.json`` and prints a Markdown table.

With ``--inks`` instead: the astronaut in cmyk with each ink in passes (``stipple.progressive.progressive_colour``,
what ``vpype stipple --order progressive`` draws) against the one-pass joint stipple of the same inks
(``stipple.colour.halftone_colour``): every ink's levels' E_N over an independent stipple of that ink alone, and
all the dots' over an independent stipple of the union.

    python bench/progressive.py [--counts 3000,10000,30000] [--pixels 256] [--out DIR] [--inks]
"""

import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
DATA = Path("/work/shared/data")
FRACTIONS = (0.25, 0.5, 0.75, 1.0)


def make_inputs(folder, pixels):
    """The cameraman, the portrait (gray) and the cat, ``pixels`` wide, as gray PNGs."""
    from skimage import data

    sources = {
        "camera": DATA / "camera.png",
        "astronaut": DATA / "astronaut.png",
        "chelsea": Path(data.__file__).parent / "chelsea.png",
    }
    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for name, source in sources.items():
        image = Image.open(source).convert("L")
        height = round(image.height * pixels / image.width)
        paths[name] = folder / f"{name}.png"
        image.resize((pixels, height), Image.LANCZOS).save(paths[name])
    return paths


def stipple(*arguments):
    """stderr of one ``stipple`` command (which must succeed)."""
    run = subprocess.run([sys.executable, "-m", "stipple", *map(str, arguments)], capture_output=True, text=True)
    if run.returncode:
        raise RuntimeError(run.stderr)
    return run.stderr, run.stdout


def travel(stderr):
    """The pen-up travel after ordering, from the command's line."""
    return float(re.search(r"pen-up travel \S+ -> (\S+)", stderr).group(1))


def measures(points_csv, image, folder, tag):
    """E_N / i.i.d. and the picture's RMSE (sigma 2 and 4 px) of a CSV of dots."""
    _, report = stipple("evaluate", points_csv, image, "--json", "-")
    picture = folder / f"{tag}.png"
    stipple("render", points_csv, "--like", image, "-o", picture)
    _, drawn = stipple("evaluate", picture, image, "--json", "-")
    sigmas = json.loads(drawn)["stipple"]
    return {
        "energy_ratio": json.loads(report)["energy_ratio_to_iid"],
        "rmse2": sigmas[0]["rmse"],
        "rmse4": sigmas[1]["rmse"],
    }


def prefix_csv(source, count, target):
    lines = source.read_text().splitlines()
    target.write_text("\n".join(lines[: count + 1]) + "\n")
    return target


def run_case(name, image, count, folder):
    """One image at one M: the measures of every prefix and of the independent stipples, and the travels."""
    case = folder / f"{name}-{count}"
    case.mkdir(exist_ok=True)
    started = time.perf_counter()
    progressive_err, _ = stipple("torus", image, "-M", count, "--order", "progressive", "-o", case / "prog.csv")
    seconds = time.perf_counter() - started
    started = time.perf_counter()
    path_err, _ = stipple("torus", image, "-M", count, "--order", "-o", case / "path.csv")
    path_seconds = time.perf_counter() - started
    entry = {"image": name, "M": count, "seconds_progressive": seconds, "seconds_path": path_seconds}
    entry["travel_progressive"], entry["travel_path"] = travel(progressive_err), travel(path_err)
    for fraction in FRACTIONS:
        part = int(round(fraction * count))
        if fraction < 1:
            stipple("torus", image, "-M", part, "-o", case / f"alone{part}.csv")
            alone = case / f"alone{part}.csv"
        else:
            alone = case / "path.csv"
        ours = measures(prefix_csv(case / "prog.csv", part, case / f"prefix{part}.csv"), image, case, f"p{part}")
        theirs = measures(alone, image, case, f"a{part}")
        entry[f"{int(fraction * 100)}%"] = {"dots": part, "progressive": ours, "independent": theirs}
    return entry


def table(summary):
    """Markdown rows: image, M, per prefix the E_N and RMSE ratios, and the travel ratio."""
    lines = [
        "| image | M | E_N ratio 25 / 50 / 75 / 100 % | RMSE ratio σ 2 px, 25 / 50 / 75 / 100 % | RMSE ratio σ 4 px "
        "| pen-up travel progressive / one path |",
        "|---|---|---|---|---|---|",
    ]
    for entry in summary:
        energy, rmse, rmse4 = [], [], []
        for fraction in FRACTIONS:
            part = entry[f"{int(fraction * 100)}%"]
            energy.append(part["progressive"]["energy_ratio"] / part["independent"]["energy_ratio"])
            rmse.append(part["progressive"]["rmse2"] / part["independent"]["rmse2"])
            rmse4.append(part["progressive"]["rmse4"] / part["independent"]["rmse4"])
        travel_ratio = entry["travel_progressive"] / entry["travel_path"]
        lines.append(
            f"| {entry['image']} | {entry['M']} | {' / '.join(f'{v:.2f}' for v in energy)} | "
            f"{' / '.join(f'{v:.2f}' for v in rmse)} | {' / '.join(f'{v:.2f}' for v in rmse4)} | "
            f"{entry['travel_progressive']:.4g} / {entry['travel_path']:.4g} "
            f"mm = {travel_ratio:.2f} |"
        )
    return "\n".join(lines)


def level_ratio(density, points):
    """E_N of ``points`` over that of an independent stipple of as many dots of ``density``."""
    from stipple.halftone import run
    from stipple.measures.evaluate import discrepancy_energy
    from stipple.torus import torus_problem

    level = torus_problem(density, len(points))
    return discrepancy_energy(level, points) / discrepancy_energy(level, run(level, seed=2).points)


def inks_case(count, pixels):
    """Markdown rows: per cmyk ink of the astronaut, its levels' E_N ratios, progressive against one pass."""
    from stipple.colour import halftone_colour
    from stipple.progressive import progressive_colour

    image = Image.open(DATA / "astronaut.png").convert("RGB")
    image = image.resize((pixels, round(image.height * pixels / image.width)), Image.LANCZOS)
    rgb = np.asarray(image, dtype=np.float64) / 255
    started = time.perf_counter()
    layers, result, counts = progressive_colour(rgb, count, separation="cmyk", seed=0)
    seconds = time.perf_counter() - started
    started = time.perf_counter()
    _, joint, one_pass = halftone_colour(rgb, count, separation="cmyk", seed=0)
    lines = [
        f"M = {count}: progressive {seconds:.1f} s, one pass {time.perf_counter() - started:.1f} s",
        "| ink | dots | E_N ratio 25 / 50 / 75 / 100 %, progressive | E_N ratio, one pass |",
        "|---|---|---|---|",
    ]
    start = 0
    for layer, passes, part in zip(layers, counts, joint.slices, strict=True):
        points = result.points[start : start + sum(passes)]
        start += sum(passes)
        ratios = [level_ratio(layer.density, points[:end]) for end in np.cumsum(passes)]
        alone = level_ratio(layer.density, one_pass.points[part])
        lines.append(f"| {layer.name} | {len(points)} | {' / '.join(f'{v:.2f}' for v in ratios)} | {alone:.2f} |")
    union = sum(layer.density for layer in layers)
    lines.append(
        f"| all dots | {count} | {level_ratio(union, result.points):.2f} | {level_ratio(union, one_pass.points):.2f} |"
    )
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", default="3000,10000,30000")
    parser.add_argument("--pixels", type=int, default=256)
    parser.add_argument("--only", default=None)
    parser.add_argument("--out", default=str(ROOT / "out" / "progressive"))
    parser.add_argument("--inks", action="store_true", help="several inks (cmyk) instead: see the docstring")
    options = parser.parse_args(argv)
    if options.inks:
        for count in (int(c) for c in options.counts.split(",")):
            print(inks_case(count, options.pixels), flush=True)
        return
    folder = Path(options.out)
    summary_path = folder / "summary.json"
    summary = json.loads(summary_path.read_text()) if summary_path.exists() else []
    done = {(entry["image"], entry["M"]) for entry in summary}
    for count in (int(c) for c in options.counts.split(",")):
        for name, image in make_inputs(folder, options.pixels).items():
            if options.only not in (None, name) or (name, count) in done:
                continue
            summary.append(run_case(name, image, count, folder))
            summary_path.write_text(json.dumps(summary, indent=2) + "\n")
            print(json.dumps(summary[-1]), flush=True)
    print(table(summary))
    alone = [entry["100%"]["independent"]["energy_ratio"] for entry in summary]
    print("E_N ratios of the independent stipples:", np.round(alone, 5))


if __name__ == "__main__":
    main()
