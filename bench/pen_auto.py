"""``-M auto`` on held-out inputs: the chosen M and the drawn plotter picture's tone curve against the input.

Inputs (from scikit-image's bundled data, none of them used to tune stipple): a light portrait (the cat
``chelsea``, gray, lightened to ``u^0.5``), a dark photo (``moon``) and a document (``page``), each scaled to
``--pixels`` wide. For each pen width, runs

    stipple torus INPUT -M auto --dot-style STYLE --pen-width PEN --width WIDTH -o out.png --png-width 2048

and ``stipple evaluate out.png INPUT --json``, and writes ``out/pen_auto/summary.json``: M, the darkest
reachable tone, and per tenth of the input's luminance the drawn luminance (sigma 2 px) and whether the tenth
is within the packing's reach (its darkness at most the reachable tone).

    python bench/pen_auto.py [--pens 0.3,0.6] [--style point] [--width 60] [--pixels 160] [--out DIR] [--reuse]

The picture is evaluated with ``--inset`` (the drawing's inset in input pixels), which registers the inset
drawing with the input: without it the page's dark edge is compared with the drawing's edge 0.8 px inwards.
"""

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]


def skimage_image(name):
    from skimage import data

    return Path(data.__file__).parent / name


def make_inputs(folder, pixels):
    """The three held-out inputs as gray PNGs ``pixels`` wide."""
    folder.mkdir(parents=True, exist_ok=True)
    recipes = {
        "light-portrait": ("chelsea.png", lambda u: u**0.5),
        "dark-photo": ("moon.png", lambda u: u),
        "document": ("page.png", lambda u: u),
    }
    paths = {}
    for name, (source, transfer) in recipes.items():
        image = Image.open(skimage_image(source)).convert("L")
        height = round(image.height * pixels / image.width)
        luminance = np.asarray(image.resize((pixels, height), Image.LANCZOS), dtype=np.float64) / 255
        paths[name] = folder / f"{name}.png"
        Image.fromarray(np.round(255 * transfer(luminance)).astype(np.uint8)).save(paths[name])
    return paths


def run_case(stipple, image, pen, options, folder):
    picture = folder / f"{image.stem}-{pen}mm-{options.style}.png"
    command = [*stipple, "torus", str(image), "-M", "auto", "--dot-style", options.style, "--pen-width", f"{pen}mm"]
    command += ["--width", f"{options.width}mm", "-o", str(picture), "--png-width", "2048", "-v"]
    log = picture.with_suffix(".log")
    if not (options.reuse and log.exists() and picture.exists()):
        log.write_text(subprocess.run(command, capture_output=True, text=True, check=True).stderr)
    chosen = [line for line in log.read_text().splitlines() if "-M auto" in line or "packing count" in line]
    inset = drawing_inset(image, int(chosen[0].split("-M auto: ")[1].split()[0]), pen, options.width)
    report = json.loads(
        subprocess.run(
            [*stipple, "evaluate", str(picture), str(image), "--json", "-", "--sigma", "2", "--inset", f"{inset:.6f}"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    )
    return chosen, report


def drawing_inset(image, count, pen, width):
    """The plotter style's inset in input pixels (``stipple.render.dots.flat_dots``): the larger of the tone radius
    and half the pen, so that ``stipple evaluate --inset`` registers the picture with the input."""
    from stipple.io.images import load_input
    from stipple.render.dots import ink_radius

    darkness = load_input(str(image))
    rows, columns = darkness.shape
    return max(ink_radius(darkness.mean() * rows * columns, count), pen * columns / width / 2)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pens", default="0.3,0.6")
    parser.add_argument("--style", default="point")
    parser.add_argument("--width", type=float, default=60.0)
    parser.add_argument("--pixels", type=int, default=160)
    parser.add_argument("--out", default=str(ROOT / "out" / "pen_auto"))
    parser.add_argument("--stipple", default=f"{sys.executable} -m stipple")
    parser.add_argument("--reuse", action="store_true", help="Re-evaluate the pictures that exist.")
    options = parser.parse_args(argv)
    folder = Path(options.out)
    stipple = options.stipple.split()
    from stipple.render.pen_count import reachable_tone

    reachable = float(reachable_tone(options.style))
    summary = []
    for name, image in make_inputs(folder, options.pixels).items():
        for pen in (float(p) for p in options.pens.split(",")):
            chosen, report = run_case(stipple, image, pen, options, folder)
            entry = {"input": name, "pen_mm": pen, "style": options.style, "stderr": chosen}
            entry.update(tone_entry(report, reachable))
            summary.append(entry)
            print(json.dumps(entry), flush=True)
    (folder / f"summary-{options.style}.json").write_text(json.dumps(summary, indent=2) + "\n")


def tone_entry(report, reachable):
    """The tone curve at sigma 2 px: per tenth, input and drawn luminance, and whether it is reachable."""
    measure = report["stipple"][0]
    tenths = []
    for tenth in measure["tone_curve"]:
        source, drawn = tenth["input"], tenth["output"]
        tenths.append(
            {"input": source, "drawn": drawn, "pixels": tenth["pixels"], "reachable": bool(1 - source <= reachable)}
        )
    worst = max((abs(t["drawn"] - t["input"]) for t in tenths if t["reachable"]), default=None)
    return {"tenths": tenths, "worst_reachable": worst, "reachable_tone": reachable}


if __name__ == "__main__":
    main()
