"""Warm frames from several seeds against the median of three cold runs, for variants of the warm frame (issue 35).

    python bench/video_seeds.py [--set WARM_LEVELS="((5, 6), (6, 10))"] [--set FRAME_ITERATIONS=8] [--clip pan ...]

One warm run of a clip is one draw: its worst frame scatters from seed to seed as much as the cold runs do. This
runs ``stipple_video`` from frame 0 of each of ``--seeds`` seeds and prints, per clip and seed, the worst frame's
local error at sigma 4 px over the median of three cold runs of that frame (seeds 0-2, ``halftone_torus``), its
PSNR at sigma 4 px below theirs, its E_N at N = 128 over theirs, and the warm frames' median seconds over the
cold runs'. ``--set NAME=VALUE`` sets a constant of ``stipple.video`` (a Python literal) before the warm runs; the
cold runs are made once per clip and kept in ``--cache`` (JSON) so that variants share them (their times then come from
another moment of the machine: compare times within one invocation only).
"""

import argparse
import ast
import json
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from video_frames import CLIPS, cold_runs, densities, frame_measures, median_measures, ratios, warm_run  # noqa: E402

import stipple.video as video_module  # noqa: E402
from stipple.torus import default_bandwidth  # noqa: E402

COLD_SEEDS = 3


def cold_reference(name, frames, count, threads):
    """The clip's bandwidth, the median of ``COLD_SEEDS`` cold runs' measures per frame, and their median seconds."""
    weights = densities(CLIPS[name](frames))
    bandwidth = default_bandwidth(count, weights[0])
    runs = [cold_runs(weights, count, bandwidth, threads, seed=seed) for seed in range(COLD_SEEDS)]
    medians = [
        median_measures([frame_measures(weights[k], run[k][0], count, threads) for run in runs]) for k in range(frames)
    ]
    seconds = statistics.median(s for run in runs for _, s in run)
    return {"bandwidth": bandwidth, "medians": medians, "seconds": seconds}


def worst_of_warm_run(name, frames, count, threads, seed, reference):
    """The worst warm frame's ratios against ``reference`` and the warm over cold seconds."""
    weights = densities(CLIPS[name](frames))
    # VideoSettings' default was bound when the module was imported: --set FRAME_ITERATIONS needs it passed.
    iterations = video_module.FRAME_ITERATIONS
    warm = warm_run(weights, count, reference["bandwidth"], threads, seed=seed, frame_iterations=iterations)
    rows = [
        ratios(frame_measures(weights[k], warm[k][0], count, threads), reference["medians"][k])
        for k in range(1, frames)
    ]
    seconds = statistics.median(s for _, s in warm[1:]) / reference["seconds"]
    return {key: max(row[key] for row in rows) for key in rows[0]} | {"warm_over_cold_seconds": seconds}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-M", "--count", type=int, default=2000)
    parser.add_argument("--frames", type=int, default=16)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--clip", action="append", choices=sorted(CLIPS), help="default: all four")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    default_cache = Path(tempfile.gettempdir()) / "stipple-video-seeds-cold.json"
    parser.add_argument("--cache", default=default_cache, help="the cold runs' measures, kept between runs")
    args = parser.parse_args()
    for assignment in args.set:
        name, _, value = assignment.partition("=")
        if not hasattr(video_module, name):
            parser.error(f"--set: stipple.video has no {name}")
        setattr(video_module, name, ast.literal_eval(value))
    cache = Path(args.cache)
    references = json.loads(cache.read_text()) if cache.exists() else {}
    for name in args.clip or list(CLIPS):
        key = f"{name} {args.frames} {args.count} {args.threads}"
        if key not in references:
            references[key] = cold_reference(name, args.frames, args.count, args.threads)
            cache.write_text(json.dumps(references))
        worst = [
            worst_of_warm_run(name, args.frames, args.count, args.threads, seed, references[key])
            for seed in range(args.seeds)
        ]
        print(
            name,
            " | ".join(
                f"worst {w['worst_over_cold']:.2f}, {w['psnr4_below_cold']:.1f} dB, "
                f"E_N {w['energy_over_cold']:.2f}, {w['warm_over_cold_seconds']:.2f} s"
                for w in worst
            ),
            flush=True,
        )


if __name__ == "__main__":
    main()
