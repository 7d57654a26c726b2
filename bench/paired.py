"""Whole commands of two versions, paired and alternated: wall time, iterations, peak memory and quality of both.

    python bench/paired.py --old /path/to/old/.venv/bin/stipple [--new CMD] [--cases portrait,dark,...]
                           [--repeats 2] [--out out/paired] [--output bench/paired.json]

For every case the inputs are made once (from ``samples/`` and scikit-image's bundled photos, none of them the
photos the speed work was tuned on except the portrait), then the old and the new command run one after the other
(old first in odd rounds, new first in even ones), ``--repeats`` times, each in its own process: wall time, peak
resident memory of the process (``wait4``'s ``ru_maxrss``), the iterations its summary line reports. The last
round's outputs of both are judged by the new version's ``stipple evaluate`` (the same measures for both): the
untruncated energy, exact-blur PSNR at sigma 1, 2, 4 px, the nearest-neighbour ratio's 1st percentile, and the
drawn picture's luminance RMSE (colour: CIEDE2000) at sigma 4 px. ``--old`` defaults to ``$STIPPLE_OLD``; without
either, only the new command runs (a fresh clone has no old version). Medians and new/old ratios are in the JSON.
``--variant LABEL=OPTIONS`` (repeatable) adds the new command with more options after the case's own, e.g.
``gpu=--backend cufinufft``, in the same alternation, with its own ratio to the old. Every command runs in the
``--out`` folder: ``python -m stipple`` puts its current directory before ``PYTHONPATH``, so a command such as
``env PYTHONPATH=/path/to/checkout python -m stipple`` started in another checkout would run that one instead
(the default ``--new`` names this checkout so).
A command's program given as a relative path is made absolute; give other paths in a command absolute.
"""

import argparse
import json
import multiprocessing
import os
import re
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "samples"


def photo(name):
    """A bundled scikit-image photo as 8-bit RGB."""
    import skimage.data

    return getattr(skimage.data, name)()


def gray_square(name, size, crop=None):
    image = photo(name) if crop is None else photo(name)[crop]
    return Image.fromarray(image).convert("L").resize((size, size), Image.Resampling.LANCZOS)


def make_inputs(folder):
    """The cases' inputs in ``folder`` (made once; deterministic)."""
    folder.mkdir(parents=True, exist_ok=True)
    makers = {
        # Held out: the cat, square, 1024² (M = 10^6); the rocket at dusk (dark, mean luminance 0.26); a 2:1
        # panorama cut from the stained-tissue micrograph; the coffee cup in colour, 300×200.
        "cat1024.png": lambda: gray_square("chelsea", 1024, np.s_[:, 75:375]),
        "rocket256.png": lambda: gray_square("rocket", 256, np.s_[:, 106:533]),
        "panorama512x256.png": lambda: (
            Image.fromarray(photo("immunohistochemistry")[128:384])
            .convert("L")
            .resize((512, 256), Image.Resampling.LANCZOS)
        ),
        "coffee300x200.png": lambda: Image.fromarray(photo("coffee")).resize((300, 200), Image.Resampling.LANCZOS),
        # A phone camera's 12 megapixels: the coffee cup, with a sensor's pixel noise, as a JPEG; a 4320 x 2160 map.
        "coffee4032x3024.jpg": lambda: noisy_photo("coffee", (4032, 3024)),
        "topo4320x2160.npy": lambda: np.asarray(
            Image.fromarray(np.load(SAMPLES / "topo.npy").astype(np.float32)).resize((4320, 2160), Image.BICUBIC)
        ),
    }
    for name, make in makers.items():
        if not (folder / name).exists():
            made = make()
            if name.endswith(".npy"):
                np.save(folder / name, made)
            else:
                made.save(folder / name, quality=92)
    return folder


def make_inputs_apart(folder):
    """``make_inputs`` in a process of its own: a command's peak memory (``wait4``'s ``ru_maxrss``) starts at this
    process's when it forks, and making the 12-megapixel photo took this one to 0.9 GB (every command of a first
    run then read 0.89 GiB or more)."""
    process = multiprocessing.get_context("spawn").Process(target=make_inputs, args=(folder,))
    process.start()
    process.join()
    if process.exitcode:
        raise SystemExit(f"making the inputs in {folder} failed (exit {process.exitcode})")
    return folder


def noisy_photo(name, size):
    """A bundled photo resized to ``size`` with Gaussian pixel noise of 4 levels (deterministic)."""
    pixels = np.asarray(Image.fromarray(photo(name)).resize(size, Image.Resampling.LANCZOS), dtype=float)
    pixels += np.random.default_rng(0).normal(0.0, 4.0, pixels.shape)
    return Image.fromarray(np.clip(np.rint(pixels), 0, 255).astype(np.uint8))


def cases(inputs):
    """name -> (command arguments after ``stipple``, input, outputs, evaluate options[, the picture's blur in input
    pixels, default 4])."""
    portrait = str(SAMPLES / "astronaut256.png")
    topo = str(SAMPLES / "topo.npy")
    camera = str(SAMPLES / "camera128.png")
    return {
        # A few seconds: the harness's own test.
        "smoke": (["torus", camera, "-M", "2000"], camera, ("png", "csv"), []),
        "portrait": (["torus", portrait, "-M", "30150"], portrait, ("png", "csv"), []),
        "dark": (["torus", str(inputs / "rocket256.png"), "-M", "30000"], inputs / "rocket256.png", ("png", "csv"), []),
        "panorama": (
            ["torus", str(inputs / "panorama512x256.png"), "-M", "40000"],
            inputs / "panorama512x256.png",
            ("png", "csv"),
            [],
        ),
        "colour": (
            ["colour", str(inputs / "coffee300x200.png"), "-M", "30000"],
            inputs / "coffee300x200.png",
            ("png", "csv"),
            [],
        ),
        "sphere": (["sphere", topo, "-M", "200000"], topo, ("csv",), []),
        "million": (["torus", str(inputs / "cat1024.png"), "-M", "1000000"], inputs / "cat1024.png", ("csv",), []),
        # The picture judged at 16 input pixels: 4 of the PNG's (1024 wide) pixels, as for the other cases.
        "photo": (
            ["torus", str(inputs / "coffee4032x3024.jpg"), "-M", "30000"],
            inputs / "coffee4032x3024.jpg",
            ("png", "csv"),
            [],
            16,
        ),
        "map": (
            ["sphere", str(inputs / "topo4320x2160.npy"), "-M", "20000"],
            inputs / "topo4320x2160.npy",
            ("csv",),
            [],
        ),
    }


def run_measured(command, timeout, cwd=None):
    """Wall seconds, the child's own peak resident memory (``wait4``), return code and stderr of one command."""
    started = time.perf_counter()
    with open(os.devnull, "wb") as devnull, open(os.devnull, "rb") as stdin:
        with tempfile.TemporaryFile() as errors:
            process = subprocess.Popen(command, stdin=stdin, stdout=devnull, stderr=errors, cwd=cwd)
            deadline = started + timeout
            while True:
                pid, status, usage = os.wait4(process.pid, os.WNOHANG)
                if pid:
                    break
                if time.perf_counter() > deadline:
                    process.kill()
                time.sleep(0.05)
            wall = time.perf_counter() - started
            process.returncode = os.waitstatus_to_exitcode(status)
            errors.seek(0)
            stderr = errors.read().decode(errors="replace")
    return {"seconds": wall, "peak_bytes": usage.ru_maxrss * 1024, "returncode": process.returncode, "stderr": stderr}


def iterations_from(stderr):
    """Iterations from the summary line (the main run's, "after N iterations")."""
    match = re.findall(r"(?:after|reached) (\d+) iterations", stderr or "")
    return int(match[0]) if match else None


def evaluate(new, outputs, source, options, cwd=None, picture_sigma=4):
    """The new version's measures of one run's outputs (``stipple evaluate`` started in ``cwd``)."""
    report = {}
    csv = outputs.get("csv")
    if csv is not None and csv.exists():
        text = subprocess.run(
            [*new, "evaluate", str(csv), str(source), *options, "--json", "-"], capture_output=True, text=True, cwd=cwd
        )
        report["points"] = json.loads(text.stdout) if text.returncode == 0 else {"error": text.stderr[-500:]}
    png = outputs.get("png")
    if png is not None and png.exists():
        text = subprocess.run(
            [*new, "evaluate", str(png), str(source), "--sigma", f"{picture_sigma:g}", "--json", "-"],
            capture_output=True,
            text=True,
            cwd=cwd,
        )
        report["picture"] = json.loads(text.stdout) if text.returncode == 0 else {"error": text.stderr[-500:]}
    return report


def summary(report):
    """The few numbers compared: untruncated energy, exact-blur PSNR, p01, picture error."""
    points = report.get("points", {})
    torus = points.get("union", points)
    out = {}
    if "untruncated_energy" in torus:
        out["untruncated_energy"] = torus["untruncated_energy"]
    if "similarity" in torus:
        out["psnr_exact"] = [round(item["psnr"], 3) for item in torus["similarity"]]
    clumps = torus.get("neighbour_distance_over_hexagonal")
    if isinstance(clumps, dict):
        out["p01"] = clumps.get("p01")
    for key in ("energy", "energy_ratio_to_iid"):
        if key in torus:
            out[key] = torus[key]
    picture = report.get("picture", {})
    for item in picture.get("stipple", []):
        for key, value in item.items():
            if key != "sigma" and isinstance(value, (int, float)):
                out[f"picture_sigma{item['sigma']:g}_{key}"] = value
    return out


def run_case(name, spec, versions, repeats, out, timeout):
    arguments, source, formats, evaluate_options, *picture_sigma = spec
    runs = {label: [] for label in versions}
    outputs = {}
    for round_ in range(repeats):
        order = list(versions) if round_ % 2 == 0 else list(versions)[::-1]
        for label in order:
            folder = out / name / label
            folder.mkdir(parents=True, exist_ok=True)
            paths = {fmt: folder / f"out.{fmt}" for fmt in formats}
            for path in paths.values():
                path.unlink(missing_ok=True)
            prefix, suffix = versions[label]
            command = [*prefix, *arguments, *suffix, *sum((["-o", str(p)] for p in paths.values()), [])]
            record = run_measured(command, timeout, cwd=out)
            record["iterations"] = iterations_from(record["stderr"])
            record["stderr"] = record["stderr"][-400:]
            runs[label].append(record)
            outputs[label] = paths
            print(
                f"{name} {label}: {record['seconds']:.1f} s, {record['peak_bytes'] / 2**30:.2f} GiB, "
                f"{record['iterations']} it, rc {record['returncode']}",
                file=sys.stderr,
                flush=True,
            )
    entry = {"command": "stipple " + shlex.join(arguments), "versions": {}}
    for label in versions:
        seconds = [item["seconds"] for item in runs[label]]
        entry["versions"][label] = {
            "command": shlex.join(versions[label][0] + versions[label][1]),
            "seconds": seconds,
            "median_seconds": statistics.median(seconds),
            "peak_gib": max(item["peak_bytes"] for item in runs[label]) / 2**30,
            "iterations": [item["iterations"] for item in runs[label]],
            "returncodes": [item["returncode"] for item in runs[label]],
            "quality": summary(
                evaluate(versions["new"][0], outputs[label], source, evaluate_options, out, *picture_sigma)
            ),
        }
    if "old" in versions:
        old = entry["versions"]["old"]
        for label in versions:
            if label == "old":
                continue
            key = "" if label == "new" else f"_{label}"
            entry[f"ratio{key}_new_over_old"] = entry["versions"][label]["median_seconds"] / old["median_seconds"]
            pairs = zip(runs[label], runs["old"], strict=True)
            entry[f"ratios{key}_per_round"] = [new["seconds"] / old_run["seconds"] for new, old_run in pairs]
    return entry


def this_checkout():
    """``python -m stipple`` of the checkout that holds this script (the commands start elsewhere, in ``--out``)."""
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    return shlex.join(["env", f"PYTHONPATH={path}", sys.executable, "-m", "stipple"])


def command_words(command):
    """``command`` split as a shell splits it, its program made absolute if given as a relative path (the commands
    run in the ``--out`` folder)."""
    words = shlex.split(command)
    if words and os.sep in words[0] and not os.path.isabs(words[0]):
        words[0] = os.path.abspath(words[0])
    return words


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", default=os.environ.get("STIPPLE_OLD"), help="the old version's stipple command")
    parser.add_argument("--new", default=this_checkout(), help="default: this checkout, with this Python")
    parser.add_argument("--cases", default="portrait,dark,panorama,colour,sphere,million")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=1800)
    parser.add_argument("--out", default="out/paired")
    parser.add_argument("--output", default="bench/paired.json")
    parser.add_argument("--variant", action="append", default=[], help="LABEL=OPTIONS: the new command with OPTIONS")
    args = parser.parse_args(argv)
    out = Path(args.out).resolve()
    if (out / "stipple").exists():
        parser.error(f"--out {out} holds a 'stipple' folder, which python -m stipple would run: choose another")
    specs = cases(make_inputs_apart(out / "inputs"))
    versions = {"new": (command_words(args.new), [])}
    for variant in args.variant:
        label, _, options = variant.partition("=")
        versions[label] = (command_words(args.new), shlex.split(options))
    if args.old:
        versions = {"old": (command_words(args.old), []), **versions}
    results = {}
    for name in args.cases.split(","):
        results[name] = run_case(name, specs[name], versions, args.repeats, out, args.timeout)
        Path(args.output).write_text(json.dumps(results, indent=1) + "\n")
    return results


if __name__ == "__main__":
    main()
