"""Benchmarks: seconds per CG iteration against the raw transforms one iteration needs.

Writes JSON (``--output``) with, per case: M, N, backend, threads, near field on or off (with its pair count),
median seconds per iteration (over ``--iterations`` iterations after as many from the start, and over those first
ones, where the dots still travel far), median seconds of the raw transforms of one iteration (measured in the
same run), their ratio, transform counts per iteration, the process's peak memory so far, and library versions.
Each near-field case is run beside the same problem without it. Quote medians; compare ratios within one run.
Scale cases (``bench/scale.py``, one process each, with its own peak memory): the torus with M = 10^6 on a
1024² image (default N), and spherical designs of strength 200 (default M) and 1000 (M = 1,002,000) timed to
their target (largest error 1e-10). Paired cases (``bench/paired.py``, with ``--old CMD`` or ``$STIPPLE_OLD``: the
whole commands of another version, e.g. the checkout before the coarse-to-fine start, alternated with this one's,
with both outputs' quality; skipped without an old version, so that a fresh clone runs the rest). Video cases
(``bench/video.py``): seconds per warm-started frame against a
cold single-image run, the still dots' moves and each frame's E_N against its cold run's, at M = 2000 and 20000.
"""

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from stipple.allocator import reuse_freed_memory
from stipple.checkpoint import LIBRARIES, library_versions
from stipple.halftone import default_threads, run
from stipple.io.images import load_density
from stipple.sphere import CellMap, from_lon_lat, sphere_problem
from stipple.torus import torus_problem
from stipple.transforms import alm_size, spherical_angles

sys.path.insert(0, str(Path(__file__).parent))
from video import clips, video_case  # noqa: E402 (bench/video.py, beside this script)

TORUS_CASES = [(30150, 650), (200000, 1300)]
SPHERE_CASES = [(200000, 1000)]
PEAKED_CASES = [(10000, None)]  # M, N (None: the default chosen from the density)
# Scale cases, each in its own process (bench/scale.py) so that each reports its own peak memory.
SCALE_CASES = [("torus", "1000000", "1024", "5"), ("design", "200", "default"), ("design", "1000", "1002000")]
QUICK_SCALE_CASES = [("torus", "20000", "256", "3"), ("design", "20", "default")]
VIDEO_CASES, QUICK_VIDEO_CASES = (2000, 20000), (500,)
SECTIONS = ("torus", "sphere", "peaked", "scale", "video")


def gaussian_bump(points, centre=(30.0, 20.0), sigma_degrees=8.0, floor=0.04):
    """A sharp Gaussian bump on a faint background: the peaked density that made 0.1 form chains."""
    angle = np.arccos(np.clip(points @ from_lon_lat(*np.array([[centre[0]], [centre[1]]]))[0], -1, 1))
    return floor + (1 - floor) * np.exp(-(angle**2) / (2 * np.radians(sigma_degrees) ** 2))


def median_iteration_seconds(problem, iterations):
    """Median wall time between consecutive CG callbacks over the first ``iterations`` (the start, where the dots
    still travel far) and over as many after them (the steady state of a long run), and transform counts per
    iteration."""
    stamps = []
    counts = []

    def record(state):
        stamps.append(time.perf_counter())
        counts.append(dict(transform_counts(problem)))
        return False

    # Without the coarse-to-fine start, whose levels' iterations (fewer dots, lower N) the callback would also see.
    run(problem, tol=1e-15, iterations=2 * iterations, settle=0, correct=False, levels=False, callback=record)
    per_iteration = {key: counts[-1][key] - counts[-2][key] for key in counts[-1]}
    gaps = np.diff(stamps)
    return float(np.median(gaps[1:iterations])), float(np.median(gaps[iterations:])), per_iteration


def transform_counts(problem):
    return problem.discrepancy.fourier.counts


def raw_torus_seconds(problem, points, repeats):
    """One iteration's NUFFTs called directly: set points on both grids, type 1 of one array on the half grid
    (the residual's rows n1 >= 0), type 2 of one and type 1 of one on the whole grid."""
    fourier = problem.discrepancy.fourier
    nufft, half_nufft = fourier.nufft, fourier.half_nufft
    single = np.ones((1, len(points)), dtype=np.complex128)
    grid = np.ones((1,) + nufft.shape, dtype=np.complex128)

    def transforms():
        nufft.set_points(points)
        half_nufft.set_points(points)
        half_nufft.type1(single)
        nufft.type2(grid)
        nufft.type1(single)

    return median_seconds(transforms, repeats)


def raw_sphere_seconds(problem, points, repeats):
    """One iteration's SHTs called directly: adjoint spin 0, synthesis spin 1, adjoint spin 1 of one field."""
    import ducc0

    fourier = problem.discrepancy.fourier
    theta, phi = spherical_angles(points)
    options = dict(
        lmax=fourier.lmax, loc=np.stack([theta, phi], axis=1), epsilon=fourier.epsilon, nthreads=fourier.threads
    )
    alm = np.ones((1, alm_size(fourier.lmax)), dtype=np.complex128)
    ones = np.ones((1, len(points)))
    pair = np.ones((2, len(points)))

    def transforms():
        ducc0.sht.adjoint_synthesis_general(map=ones, spin=0, **options)
        ducc0.sht.synthesis_general(alm=alm, spin=1, mode="DERIV1", **options)
        ducc0.sht.adjoint_synthesis_general(map=pair, spin=1, mode="DERIV1", **options)

    return median_seconds(transforms, repeats)


def median_seconds(function, repeats):
    timings = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        timings.append(time.perf_counter() - started)
    return float(np.median(timings))


def case(problem, raw_seconds, name, backend, threads, iterations):
    points = problem.sample(np.random.default_rng(0), problem.n_points)
    start_seconds, seconds, counts = median_iteration_seconds(problem, iterations)
    raw = raw_seconds(problem, points, max(5, iterations // 2))
    near = problem.objective.terms[-1] if problem.settings.get("near_field") else None
    return {
        "domain": problem.domain,
        "input": name,
        "M": problem.n_points,
        "N": problem.bandwidth,
        "backend": backend,
        "threads": threads,
        "epsilon": problem.discrepancy.fourier.epsilon,
        "iterations_timed": iterations,
        "seconds_per_iteration": seconds,
        "seconds_per_iteration_at_start": start_seconds,
        "raw_transform_seconds_per_iteration": raw,
        "ratio_iteration_to_raw": seconds / raw,
        "transforms_per_iteration": counts,
        "near_field": near is not None,
        "near_field_pairs": near.pair_count if near is not None else 0,
        "peak_memory_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def scale_case(arguments):
    """One case of ``bench/scale.py`` in a fresh process; its JSON line."""
    script = Path(__file__).with_name("scale.py")
    completed = subprocess.run([sys.executable, str(script), *arguments], capture_output=True, text=True, check=True)
    return {"domain": "torus" if arguments[0] == "torus" else "sphere", "scale": True, **json.loads(completed.stdout)}


def versions():
    """Python's and the libraries' versions, the GPU's transforms too ("unknown" where one is not installed)."""
    return {"python": platform.python_version(), **library_versions(LIBRARIES + ("cufinufft",))}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default="bench/results.json")
    parser.add_argument("--iterations", type=int, default=20)
    parser.add_argument("--threads", type=int, default=default_threads())
    parser.add_argument("--quick", action="store_true", help="small cases only (smoke test)")
    parser.add_argument("--backends", default="ducc0,finufft", help="torus backends (cufinufft: the GPU's)")
    parser.add_argument("--sections", default=",".join(SECTIONS), help="which of " + ", ".join(SECTIONS))
    parser.add_argument(
        "--old", default=os.environ.get("STIPPLE_OLD"), help="another version's stipple command: paired cases"
    )
    parser.add_argument("--paired-cases", default="portrait,dark,panorama,colour,sphere,million")
    parser.add_argument("--paired-repeats", type=int, default=2)
    args = parser.parse_args(argv)
    reuse_freed_memory()  # as the command line does
    portrait = load_density("samples/astronaut256.png")
    topography = CellMap(load_density("samples/topo.npy"))
    results = []

    def record(entry):
        results.append(entry)
        print(json.dumps(entry), file=sys.stderr)

    sections = args.sections.split(",")
    backends = args.backends.split(",")
    torus_variants = [(backends[0], True), (backends[0], False)] + [(backend, True) for backend in backends[1:]]
    for n_points, bandwidth in [(2000, 128)] if args.quick else TORUS_CASES * ("torus" in sections):
        for backend, near_field in torus_variants:
            problem = torus_problem(
                portrait, n_points, bandwidth, backend=backend, threads=args.threads, near_field=near_field
            )
            record(case(problem, raw_torus_seconds, "samples/astronaut256.png", backend, args.threads, args.iterations))
    for n_points, bandwidth in [(2000, 64)] if args.quick else SPHERE_CASES * ("sphere" in sections):
        for near_field in (True, False):
            problem = sphere_problem(topography, n_points, bandwidth, threads=args.threads, near_field=near_field)
            record(case(problem, raw_sphere_seconds, "samples/topo.npy", "ducc0.sht", args.threads, args.iterations))
    for n_points, bandwidth in [(2000, None)] if args.quick else PEAKED_CASES * ("peaked" in sections):
        for near_field in (True, False):
            problem = sphere_problem(gaussian_bump, n_points, bandwidth, threads=args.threads, near_field=near_field)
            record(case(problem, raw_sphere_seconds, "gaussian bump", "ducc0.sht", args.threads, args.iterations))
    for arguments in QUICK_SCALE_CASES if args.quick else SCALE_CASES * ("scale" in sections):
        record(scale_case(arguments))
    for count in QUICK_VIDEO_CASES if args.quick else VIDEO_CASES * ("video" in sections):
        for name, clip in clips(count, 6 if args.quick else 24, real=False):
            record({"video": True, **video_case(clip, count, args.threads, name)})
    report = {"machine": platform.machine(), "cpus": default_threads(), "versions": versions(), "cases": results}
    if args.old:
        from paired import main as paired_main  # bench/paired.py, beside this script

        report["paired"] = paired_main(
            ["--old", args.old, "--cases", "smoke" if args.quick else args.paired_cases]
            + ["--repeats", str(args.paired_repeats), "--output", str(Path(args.output).with_name("paired.json"))]
        )
    with open(args.output, "w") as stream:
        json.dump(report, stream, indent=2)
        stream.write("\n")
    print(f"wrote {args.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
