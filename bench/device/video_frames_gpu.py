"""Stippled video on two backends, frame by frame: issue 35's warm frames on the GPU (cufinufft) against the CPU.

    python bench/device/video_frames_gpu.py [--frames 8] [--backends ducc0,cufinufft] [--json OUT]

For the bench's disc and fade clips (gray) and its colour clip (cmyk, measured on the union of the inks):
``stipple_video`` with each backend, the same settings and threads; per frame E_N at N = 128 (second backend
over first) and the PSNR of the exactly blurred dots at sigma 4 px (second minus first; both as
``bench/video_frames.py`` measures them), and the median seconds of the warm frames of each. The backends agree
to rounding per transform, so their frames drift apart slowly: the check is that the second's frames are as good
as the first's, not the same bits.
"""

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from clips import colour_clip, disc_clip, fade_clip  # noqa: E402
from video import densities  # noqa: E402
from video_frames import frame_measures  # noqa: E402

from stipple.halftone import default_threads  # noqa: E402
from stipple.torus import default_bandwidth  # noqa: E402
from stipple.video import VideoSettings, stipple_video  # noqa: E402

COUNT = 2000


def frames_of(clip, backend, bandwidth, palette=None):
    """``(frames, seconds)`` of ``stipple_video`` on ``backend``."""
    settings = VideoSettings(n_points=COUNT, bandwidth=bandwidth, backend=backend, palette=palette)
    done, started = [], time.perf_counter()
    stipple_video(enumerate(clip), settings, on_frame=done.append)
    return done, time.perf_counter() - started


def compare(name, clip, backends, palette=None):
    """``clip``: darkness frames, or RGB frames in [0, 1] with a ``palette``."""
    bandwidth = default_bandwidth(COUNT, clip[0] if palette is None else 1 - clip[0].mean(axis=2))
    runs = {backend: frames_of(clip, backend, bandwidth, palette) for backend in backends}
    first, second = (runs[backend][0] for backend in backends)
    per_frame = []
    for one, other in zip(first, second, strict=True):
        weights = one.density if palette is None else one.density.sum(axis=0)
        measures = [frame_measures(weights, frame.points, COUNT, default_threads()) for frame in (one, other)]
        per_frame.append(
            {
                "energy_ratio": measures[1]["energy"] / measures[0]["energy"],
                "psnr4_difference": measures[1]["psnr"][-1] - measures[0]["psnr"][-1],
            }
        )
    return {
        "clip": name,
        "backends": list(backends),
        "frames": len(per_frame),
        "worst_energy_ratio": max(row["energy_ratio"] for row in per_frame),
        "worst_psnr4_difference": min(row["psnr4_difference"] for row in per_frame),
        "warm_seconds": {b: statistics.median(f.seconds for f in frames[1:]) for b, (frames, _) in runs.items()},
        "total_seconds": {b: seconds for b, (_, seconds) in runs.items()},
        "per_frame": per_frame,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--backends", default="ducc0,cufinufft", help="two backends, the reference first")
    parser.add_argument("--json")
    args = parser.parse_args()
    backends = tuple(args.backends.split(","))
    cases = []
    for name, make in (("disc", disc_clip), ("fade", fade_clip)):
        cases.append(compare(name, densities(make(args.frames)), backends))
        print(json.dumps({k: v for k, v in cases[-1].items() if k != "per_frame"}), flush=True)
    colour = [frame / 255.0 for frame in colour_clip(args.frames)]
    cases.append(compare("colour", colour, backends, palette="cmyk"))
    print(json.dumps({k: v for k, v in cases[-1].items() if k != "per_frame"}), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(cases, indent=1))


if __name__ == "__main__":
    main()
