"""Stippled video (``stipple.video``): coherence, quality and speed of warm-started frames against cold runs.

    python bench/video.py [-M 2000 -M 20000] [--frames 24] [--threads 2] [--real] [--chunk L] [--json OUT]

Clip: ``bench/clips.py``'s still gradient with a dark disc moving across its lower part, 160 x 120 pixels for
M <= 5000 and 480 x 360 above (about 0.1 dots per pixel either way); ``--real`` also scikit-image's 24-frame GIF
(a real, if tiny, clip) scaled 8 x. Per M:

* ``warm``: ``stipple_video`` (frame 0 cold, every later frame warm-started from the previous one's dots);
* ``cold``: every frame stippled on its own (``halftone_torus``, seed 0): independent per-frame runs.

Measured: in the still region (pixels farther than two local dot spacings from every pixel that changes), each
dot's move between consecutive frames over the local hexagonal spacing ``sqrt(2 / (sqrt(3) rho))``, median and
95th percentile (``warm``: dot i to dot i; ``cold``: to the nearest dot of the next frame, a lower bound of any
matching); each frame's bandlimited ``E_N`` over its cold run's (worst frame); seconds per frame (median of the
warm frames, and of the cold runs) and their ratio. ``--chunk L``: the clip also split into chunks of L frames,
each started from the key frame's dots (frame 0's cold run), as a cluster would run them: the still dots' moves
at the seams against those within chunks.
"""

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).parent))
from clips import gradient_clip, real_clip, still_mask  # noqa: E402

from stipple.measures.evaluate import discrepancy_energy  # noqa: E402
from stipple.torus import default_bandwidth, halftone_torus, torus_problem  # noqa: E402
from stipple.video import VideoSettings, stipple_video  # noqa: E402


def densities(clip):
    """Darkness ``w = 1 - gray`` of uint8 gray or RGB frames (Rec. 601 luma)."""
    frames = [np.asarray(f, float) @ [0.299, 0.587, 0.114] if np.ndim(f) == 3 else np.asarray(f, float) for f in clip]
    return [1.0 - frame / 255.0 for frame in frames]


def spacing(weights, pixels, count):
    """Hexagonal spacing of ``count`` dots at the density's value under each of ``pixels`` (x, y)."""
    rows, columns = weights.shape
    j = np.clip(pixels[:, 0].astype(int), 0, columns - 1)
    i = np.clip(pixels[:, 1].astype(int), 0, rows - 1)
    rho = count * weights[i, j] / weights.sum()
    return np.sqrt(2 / (np.sqrt(3) * np.maximum(rho, 1e-12)))


def pair_moves(before, after, weights, mask, identity):
    """Moves over the local spacing of the dots of ``before`` (pixels) in the still ``mask``, to ``after``:
    dot i to dot i (``identity``) or to the nearest dot."""
    rows, columns = weights.shape
    i = np.clip(before[:, 1].astype(int), 0, rows - 1)
    j = np.clip(before[:, 0].astype(int), 0, columns - 1)
    still = mask[i, j]
    if identity:
        delta = np.abs(after[still] - before[still])
        delta = np.minimum(delta, [columns, rows] - delta)  # the torus wraps
        distance = np.hypot(*delta.T)
    else:
        distance, _ = cKDTree(after, boxsize=[columns, rows]).query(before[still])
    return distance / spacing(weights, before[still], len(before))


def summary(moves):
    moves = np.concatenate(moves)
    return {"median": float(np.median(moves)), "p95": float(np.percentile(moves, 95))}


def still_moves(frames, weights, mask, identity):
    """``pair_moves`` between consecutive frames, median and 95th percentile."""
    pairs = zip(frames, frames[1:], weights[1:], strict=False)
    return summary([pair_moves(a, b, w, mask, identity) for a, b, w in pairs])


def video_case(clip, count, threads, name):
    """Every measure of the module's docstring for one clip and M."""
    weights = densities(clip)
    rows, columns = weights[0].shape
    scale = np.array([columns, rows])
    bandwidth = default_bandwidth(count, weights[0])
    warm = []
    result = stipple_video(
        enumerate(weights),
        VideoSettings(n_points=count, bandwidth=bandwidth, threads=threads),
        on_frame=lambda frame: warm.append((frame.points, frame.seconds)),
    )
    cold = []
    for w in weights:
        started = time.perf_counter()
        points = halftone_torus(w, count, bandwidth, threads=threads, seed=0).points
        cold.append((points, time.perf_counter() - started))
    ratios = []
    for w, (warm_points, _), (cold_points, _) in zip(weights, warm, cold, strict=True):
        problem = torus_problem(w, count, bandwidth, threads=threads, near_field=False)
        ratios.append(discrepancy_energy(problem, warm_points) / discrepancy_energy(problem, cold_points))
    margin = 2 * float(np.median(spacing(weights[0], warm[0][0] * scale, count)))
    mask = still_mask([np.round(255 * w) for w in weights], margin)
    warm_seconds = statistics.median(s for _, s in warm[1:])
    cold_seconds = statistics.median(s for _, s in cold)
    return {
        "clip": name,
        "M": count,
        "N": bandwidth,
        "frames": len(weights),
        "size": [columns, rows],
        "threads": threads,
        "still_fraction": float(mask.mean()),
        "warm_still_move": still_moves([p * scale for p, _ in warm], weights, mask, identity=True),
        "cold_still_move": still_moves([p * scale for p, _ in cold], weights, mask, identity=False),
        "energy_over_cold": {"max": float(max(ratios)), "median": float(np.median(ratios))},
        "seconds_per_warm_frame": warm_seconds,
        "seconds_per_cold_run": cold_seconds,
        "cold_over_warm": cold_seconds / warm_seconds,
        "message": result.message,
    }


def clips(count, frames, real):
    """``(name, clip)`` pairs for M = ``count``."""
    width, height = (160, 120) if count <= 5000 else (480, 360)
    yield f"gradient {width}x{height}", gradient_clip(frames, width, height)
    if real and (clip := real_clip()) is not None:
        yield "scikit-image GIF x8", clip


def seam_case(clip, count, chunk, threads, name):
    """A clip split into chunks of ``chunk`` frames, each warm-started from the key frame (frame 0's cold run;
    ``stipple_video(..., key=(points, w))``), as a cluster would run them: still dots' moves at the seams (the
    first frame of a chunk against the last of the one before) and within chunks."""
    weights = densities(clip)
    rows, columns = weights[0].shape
    scale = np.array([columns, rows])
    bandwidth = default_bandwidth(count, weights[0])
    key = halftone_torus(weights[0], count, bandwidth, threads=threads, seed=0).points
    points = []
    settings = VideoSettings(n_points=count, bandwidth=bandwidth, threads=threads)
    for start in range(0, len(weights), chunk):
        part = weights[start : start + chunk]
        stipple_video(
            enumerate(part), settings, key=(key, weights[0]), on_frame=lambda f: points.append(f.points * scale)
        )
    margin = 2 * float(np.median(spacing(weights[0], key * scale, count)))
    mask = still_mask([np.round(255 * w) for w in weights], margin)
    seams = set(range(chunk, len(weights), chunk))
    moves = {"seam": [], "within": []}
    for k in range(1, len(weights)):
        moves["seam" if k in seams else "within"].append(pair_moves(points[k - 1], points[k], weights[k], mask, True))
    moves = {label: summary(values) for label, values in moves.items()}
    return {"clip": name, "M": count, "chunk": chunk, "frames": len(weights), "still_move": moves}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-M", "--count", type=int, action="append", help="dots (default 2000 and 20000)")
    parser.add_argument("--frames", type=int, default=24)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--real", action="store_true", help="also the real clip (scikit-image's GIF)")
    parser.add_argument("--chunk", type=int, help="also split the clip into chunks of this many frames")
    parser.add_argument("--json", help="write the cases as JSON here")
    args = parser.parse_args()
    cases = []
    for count in args.count or (2000, 20000):
        for name, clip in clips(count, args.frames, args.real):
            cases.append(video_case(clip, count, args.threads, name))
            print(json.dumps(cases[-1]), flush=True)
            if args.chunk:
                cases.append(seam_case(clip, count, args.chunk, args.threads, name))
                print(json.dumps(cases[-1]), flush=True)
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(cases, handle, indent=1)


if __name__ == "__main__":
    main()
