"""Benchmarks: seconds per CG iteration against the raw transforms one iteration needs.

Writes JSON (``--output``) with, per case: M, N, backend, threads, median seconds per iteration,
median seconds of the raw transforms of one iteration (measured in the same run), their ratio,
transform counts per iteration, and library versions. Quote medians; compare ratios within one run.
"""

import argparse
import json
import platform
import sys
import time
from importlib.metadata import version

import numpy as np

from stipple.halftone import default_threads, run
from stipple.inputs import load_density
from stipple.torus import torus_problem

TORUS_CASES = [(30150, 650), (200000, 1300)]


def median_iteration_seconds(problem, iterations):
    """Median wall time between consecutive CG callbacks, and transform counts per iteration."""
    stamps = []
    counts = []

    def record(state):
        stamps.append(time.perf_counter())
        counts.append(dict(transform_counts(problem)))
        return False

    run(problem, tol=1e-15, iterations=iterations, callback=record)
    per_iteration = {key: counts[-1][key] - counts[-2][key] for key in counts[-1]}
    return float(np.median(np.diff(stamps)[1:])), per_iteration


def transform_counts(problem):
    fourier = problem.objective.fourier
    return getattr(fourier, "nufft", fourier).counts


def raw_torus_seconds(problem, points, repeats):
    """One iteration's transforms called directly: set points, 1+2 type-1 and 1+2 type-2 (batched as in CG)."""
    nufft = problem.objective.fourier.nufft
    values = np.ones((1, len(points)), dtype=np.complex128)
    pair = np.ones((2, len(points)), dtype=np.complex128)
    grid = np.ones((1,) + nufft.shape, dtype=np.complex128)
    grids = np.ones((2,) + nufft.shape, dtype=np.complex128)
    timings = []
    for _ in range(repeats):
        started = time.perf_counter()
        nufft.set_points(points)
        nufft.type1(values)
        nufft.type2(grid)
        nufft.type1(pair)
        nufft.type2(grids)
        timings.append(time.perf_counter() - started)
    return float(np.median(timings))


def torus_case(weights, n_points, bandwidth, backend, threads, iterations):
    problem = torus_problem(weights, n_points, bandwidth, backend=backend, threads=threads)
    points = problem.sample(np.random.default_rng(0), n_points)
    seconds, counts = median_iteration_seconds(problem, iterations)
    raw = raw_torus_seconds(problem, points, max(5, iterations // 2))
    return {
        "domain": "torus",
        "input": "samples/astronaut256.png",
        "M": n_points,
        "N": bandwidth,
        "backend": backend,
        "threads": threads,
        "epsilon": problem.objective.fourier.nufft.epsilon,
        "iterations_timed": iterations,
        "seconds_per_iteration": seconds,
        "raw_transform_seconds_per_iteration": raw,
        "ratio_iteration_to_raw": seconds / raw,
        "transforms_per_iteration": counts,
    }


def versions():
    names = ["numpy", "scipy", "ducc0", "finufft", "stipple"]
    return {"python": platform.python_version(), **{name: version(name) for name in names}}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default="bench/results.json")
    parser.add_argument("--iterations", type=int, default=20)
    parser.add_argument("--threads", type=int, default=default_threads())
    parser.add_argument("--quick", action="store_true", help="small cases only (smoke test)")
    args = parser.parse_args(argv)
    weights = load_density("samples/astronaut256.png")
    cases = [(2000, 128)] if args.quick else TORUS_CASES
    results = []
    for n_points, bandwidth in cases:
        for backend in ("ducc0", "finufft"):
            result = torus_case(weights, n_points, bandwidth, backend, args.threads, args.iterations)
            print(json.dumps(result), file=sys.stderr)
            results.append(result)
    report = {"machine": platform.machine(), "cpus": default_threads(), "versions": versions(), "cases": results}
    with open(args.output, "w") as stream:
        json.dump(report, stream, indent=2)
        stream.write("\n")
    print(f"wrote {args.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
