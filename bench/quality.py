"""Quality harness: run the ``stipple`` CLI with its defaults on fixed inputs and judge the points.

For every input of a set (``default`` or ``holdout``, made from ``samples/``-style data and formulas into
``--out``), runs ``stipple torus|sphere INPUT -M M -o points.csv`` (plus ``--range 0 1`` for ``.npy`` maps, so
that their background is kept; nothing else), times it, evaluates the points with ``stipple.measures.evaluate`` and
writes ``summary-SET.json`` and a zoomed crop ``NAME-crop.png`` of the densest region (black discs on white).

    python bench/quality.py [--set default|holdout] [--only NAME] [--timeout 300] [--stipple CMD] [--out DIR]
                            [--reuse]

``--reuse`` skips the runs whose ``points.csv`` exists (re-evaluates them; ``seconds`` is then taken from the
previous summary if there is one). A run past ``--timeout`` gets SIGTERM, so the CLI writes its points; the
entry says ``"timed_out": true``.
"""

import argparse
import json
import re
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw
from scipy import ndimage

from stipple.measures.evaluate import local_spacing

ROOT = Path(__file__).resolve().parents[1]
DATA = Path("/work/shared/data")
SAMPLES = ROOT / "samples"
CROP_PIXELS = 720
DISC_FRACTION = 0.3  # disc radius as a fraction of the hexagonal spacing at the crop's densest point


def source(name):
    """A data file from ``samples/`` if shipped there, else from the shared data directory."""
    for folder in (SAMPLES, DATA):
        if (folder / name).exists():
            return folder / name
    raise FileNotFoundError(name)


def gray(name):
    """Luminance in [0, 1] of a PNG."""
    return np.asarray(Image.open(source(name)).convert("L"), dtype=np.float64) / 255


def save_gray(path, luminance):
    Image.fromarray(np.round(np.clip(luminance, 0, 1) * 255).astype(np.uint8)).save(path)


def strip(name, width, height, top):
    """A ``width × height`` band of the photo scaled to ``width`` pixels wide, starting at row ``top``."""
    image = Image.open(source(name)).convert("L").resize((width, width), Image.Resampling.BICUBIC)
    return np.asarray(image, dtype=np.float64)[top : top + height] / 255


def silhouette(name, threshold):
    """Pure black/white: black (dots) where the luminance is below ``threshold``."""
    return (gray(name) >= threshold).astype(np.float64)


def darkened(name, mean):
    """``u**g`` with ``g`` found by bisection so that the mean luminance is ``mean``."""
    luminance = gray(name)
    low, high = 1.0, 50.0
    for _ in range(60):
        middle = (low + high) / 2
        low, high = (middle, high) if np.mean(luminance**middle) > mean else (low, middle)
    return luminance ** ((low + high) / 2)


def grid_vectors(rows):
    """Unit vectors of the cell centres of a ``rows × 2 rows`` equirectangular map (column 0 at 0° E)."""
    theta = (np.arange(rows) + 0.5) * np.pi / rows
    phi = (np.arange(2 * rows) + 0.5) * np.pi / rows
    theta, phi = np.meshgrid(theta, phi, indexing="ij")
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def direction(longitude, latitude):
    lon, lat = np.radians(longitude), np.radians(latitude)
    return np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])


def bump(longitude, latitude, sigma_degrees, background, rows=360):
    """``background + (1 - background) exp(-d² / 2σ²)`` with ``d`` the angle to the centre: values in [bg, 1]."""
    angle = np.arccos(np.clip(grid_vectors(rows) @ direction(longitude, latitude), -1, 1))
    return background + (1 - background) * np.exp(-(angle**2) / (2 * np.radians(sigma_degrees) ** 2))


def relief(power):
    """``samples/topo.npy`` rescaled linearly to [0, 1], then raised to ``power``."""
    topo = np.load(source("topo.npy")).astype(np.float64)
    return ((topo - topo.min()) / np.ptp(topo)) ** power


SETS = {
    "default": [
        ("strip6x1", "torus", 5000, lambda: strip("astronaut.png", 1200, 200, 260)),
        ("silhouette", "torus", 8000, lambda: silhouette("camera.png", 0.35)),
        ("dark", "torus", 10000, lambda: darkened("astronaut.png", 0.2)),
        ("bump8", "sphere", 10000, lambda: bump(30, 20, 8, 0.04)),
        ("relief3", "sphere", 20000, lambda: relief(3)),
    ],
    "holdout": [
        ("strip4x1", "torus", 6000, lambda: strip("camera.png", 1200, 300, 150)),
        ("silhouette2", "torus", 7000, lambda: silhouette("astronaut.png", 0.5)),
        ("dark2", "torus", 12000, lambda: darkened("camera.png", 0.15)),
        ("bump5", "sphere", 12000, lambda: bump(200, -35, 5, 0.02)),
        ("relief4", "sphere", 20000, lambda: relief(4)),
    ],
}


def write_input(folder, name, domain, make):
    """Write the input file (``.png`` for the torus, ``.npy`` map for the sphere); returns its path."""
    values = make()
    if domain == "torus":
        path = folder / f"{name}.png"
        save_gray(path, values)
    else:
        path = folder / f"{name}.npy"
        np.save(path, values.astype(np.float64))
    return path


def run_cli(command, timeout):
    """Run ``command``; SIGTERM after ``timeout`` s (the CLI then writes its points). Returns (rc, stderr, s, late)."""
    started = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    late = False
    try:
        _, stderr = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        late = True
        process.send_signal(signal.SIGTERM)
        try:
            _, stderr = process.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            process.kill()
            _, stderr = process.communicate()
    return process.returncode, stderr, time.perf_counter() - started, late


def iterations_from(stderr):
    """Iteration count from the CLI's summary line, or None."""
    match = re.search(r"(?:after|reached|iteration) (\d+)", stderr or "")
    return int(match.group(1)) if match else None


def evaluate(domain, input_path, points_path, count):
    """The library's evaluation of the points; returns the report dict and the points (unit / vectors)."""
    from stipple.io.images import load_density
    from stipple.measures.evaluate import evaluate_sphere, evaluate_torus
    from stipple.pipelines.inputs import read_points

    _, points = read_points(str(points_path))
    if domain == "torus":
        from stipple.torus import torus_problem

        weights = load_density(str(input_path))
        unit = np.mod(points / np.array([weights.shape[1], weights.shape[0]]), 1.0)
        problem = torus_problem(weights, len(unit), None, epsilon=1e-10, bandwidth_factor=1.0)
        return evaluate_torus(problem, unit, weights), unit, weights
    from stipple.sphere import CellMap, sphere_problem

    density = CellMap(load_density(str(input_path), value_range=(0.0, 1.0)))
    problem = sphere_problem(density, len(points), None, epsilon=1e-12, precondition=False, bandwidth_factor=1.0)
    return evaluate_sphere(problem, points, density), points, density.values


def draw_discs(xy, radius, size):
    """Black discs of ``radius`` (crop pixels) at ``xy`` (crop pixels) on a white ``size × size`` image."""
    image = Image.new("L", (size, size), 255)
    draw = ImageDraw.Draw(image)
    for x, y in xy:
        draw.ellipse([x - radius, y - radius, x + radius, y + radius], fill=0)
    return image


def torus_crop(unit, weights):
    """Square crop (side ``max(W, H) / 6``, at most the short side) around the smoothed density's maximum."""
    rows, columns = weights.shape
    longest = max(rows, columns)
    side = min(longest / 6, rows, columns)
    smooth = ndimage.gaussian_filter(weights, side / 4, mode="wrap")
    row, column = np.unravel_index(np.argmax(smooth), smooth.shape)
    size = np.array([columns, rows], dtype=float)
    offset = np.mod(unit * size - [column + 0.5, row + 0.5] + size / 2, size) - size / 2
    inside = np.all(np.abs(offset) < side / 2, axis=1)
    scale = CROP_PIXELS / side
    # Local density in dots per pixel² at the crop centre: M w / sum(w).
    peak = len(unit) * smooth[row, column] / weights.sum()
    radius = DISC_FRACTION * local_spacing(peak) * scale
    return draw_discs((offset[inside] + side / 2) * scale, radius, CROP_PIXELS)


def sphere_crop(points, values, half_width=0.25):
    """Orthographic view centred on the smoothed map's maximum, ``|x|, |y| < half_width`` (zoomed)."""
    rows = values.shape[0]
    smooth = ndimage.gaussian_filter(values, rows / 60, mode=("nearest", "wrap"))
    row, column = np.unravel_index(np.argmax(smooth), smooth.shape)
    centre = grid_vectors(rows)[row, column]
    east = np.cross([0.0, 0.0, 1.0], centre)
    east = east / np.linalg.norm(east) if np.linalg.norm(east) > 1e-9 else np.array([1.0, 0.0, 0.0])
    north = np.cross(centre, east)
    xy = np.stack([points @ east, -(points @ north)], axis=1)
    inside = (points @ centre > 0) & np.all(np.abs(xy) < half_width, axis=1)
    scale = CROP_PIXELS / (2 * half_width)
    edges = np.cos(np.linspace(0, np.pi, rows + 1))
    mass = np.sum(values * (edges[:-1] - edges[1:])[:, None]) * 2 * np.pi / values.shape[1]
    peak = len(points) * smooth[row, column] / mass
    radius = DISC_FRACTION * local_spacing(peak) * scale
    return draw_discs((xy[inside] + half_width) * scale, radius, CROP_PIXELS)


def judge(entry, report):
    ratios = report.get("neighbour_distance_over_hexagonal", {})
    entry.update(
        bandwidth=report["bandwidth"],
        energy_ratio_to_iid=report["energy_ratio_to_iid"],
        **{key: ratios.get(key) for key in ("p01", "p05", "median", "min")},
    )
    for key in ("median_neighbour_distance_pixels", "median_neighbour_distance_radians", "cap_discrepancy"):
        if key in report:
            entry[key] = report[key]


def run_case(case, options, previous):
    name, domain, count, make = case
    folder = Path(options.out) / options.set
    folder.mkdir(parents=True, exist_ok=True)
    input_path = write_input(folder, name, domain, make)
    points_path = folder / f"{name}-points.csv"
    entry = {"input": name, "domain": domain, "M": count}
    if options.reuse and points_path.exists():
        kept = ("seconds", "iterations", "returncode", "timed_out", "message")
        entry.update({key: previous.get(key) for key in kept})
    else:
        points_path.unlink(missing_ok=True)
        command = shlex.split(options.stipple) + [domain, str(input_path), "-M", str(count), "-o", str(points_path)]
        if domain == "sphere":
            command += ["--range", "0", "1"]
        returncode, stderr, seconds, late = run_cli(command, options.timeout)
        entry.update(seconds=round(seconds, 2), iterations=iterations_from(stderr), returncode=returncode)
        entry.update(timed_out=late, message=(stderr or "").strip().splitlines()[-1:] or None)
        if not points_path.exists():
            return entry
    started = time.perf_counter()
    report, points, values = evaluate(domain, input_path, points_path, count)
    entry["evaluate_seconds"] = round(time.perf_counter() - started, 2)
    judge(entry, report)
    crop = torus_crop(points, values) if domain == "torus" else sphere_crop(points, values)
    crop.save(folder / f"{name}-crop.png", optimize=True)
    return entry


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--set", choices=sorted(SETS), default="default")
    parser.add_argument("--only", help="run one input of the set (by name)")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per run (then SIGTERM)")
    parser.add_argument("--stipple", default=f"{shlex.quote(sys.executable)} -m stipple", help="the CLI command")
    parser.add_argument("--out", default="out/quality")
    parser.add_argument("--reuse", action="store_true", help="re-evaluate existing points instead of running")
    options = parser.parse_args(argv)
    cases = [case for case in SETS[options.set] if options.only in (None, case[0])]
    if not cases:
        parser.error(f"no input {options.only!r} in set {options.set}: {[case[0] for case in SETS[options.set]]}")
    summary_path = Path(options.out) / f"summary-{options.set}.json"
    old = json.loads(summary_path.read_text()) if summary_path.exists() else {"results": []}
    previous = {item["input"]: item for item in old["results"]}
    for case in cases:
        entry = run_case(case, options, previous.get(case[0], {}))
        previous[case[0]] = entry
        print(json.dumps(entry), flush=True)
        order = [case[0] for case in SETS[options.set]]
        results = [previous[key] for key in order if key in previous]
        summary_path.write_text(json.dumps({"set": options.set, "results": results}, indent=2) + "\n")


if __name__ == "__main__":
    main()
