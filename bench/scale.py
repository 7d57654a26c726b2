"""Scale cases of ``make bench``, one per process so that each reports its own peak memory.

    python bench/scale.py torus M SIZE ITERATIONS   # M dots on the portrait upsampled to SIZE² pixels, default N
    python bench/scale.py design T M|default        # a spherical design of strength T to largest error 1e-10

Prints one JSON object: M, N, threads, seconds per iteration (median at the start and after it for the torus),
iterations and seconds to the target for designs, the process's peak memory, and the transforms used.
"""

import json
import resource
import sys
import time

import numpy as np
from PIL import Image

from stipple.allocator import reuse_freed_memory
from stipple.design import spherical_design
from stipple.halftone import default_threads, run
from stipple.torus import torus_problem


def peak_memory_mb():
    """This process's peak resident memory: ``VmHWM`` (Linux keeps ``ru_maxrss`` across exec, so a child of a big
    process would report its parent's size), else ``ru_maxrss``."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def portrait(size):
    """``samples/astronaut256.png`` resized to ``size``² (bicubic) as darkness weights in [0, 1]."""
    image = Image.open("samples/astronaut256.png").convert("L").resize((size, size), Image.BICUBIC)
    return 1 - np.asarray(image, dtype=np.float64) / 255


def torus_case(n_points, size, iterations):
    """Default problem (N from M, near field, threads: all CPUs); medians over ``iterations`` and as many after them."""
    started = time.perf_counter()
    problem = torus_problem(portrait(size), n_points)
    setup = time.perf_counter() - started
    stamps = []
    run(
        problem,
        tol=1e-15,
        iterations=2 * iterations,
        settle=0,
        correct=False,
        levels=False,  # full-size iterations only: the coarse-to-fine start's levels would be timed too
        callback=lambda state: stamps.append(time.perf_counter()),
    )
    gaps = np.diff(stamps)
    nufft = problem.discrepancy.fourier.nufft
    return {
        "case": f"torus M={n_points} on the portrait at {size}x{size}",
        "M": n_points,
        "N": problem.bandwidth,
        "threads": nufft.threads,
        "epsilon": nufft.epsilon,
        "setup_seconds": setup,
        "seconds_per_iteration_at_start": float(np.median(gaps[1:iterations])),
        "seconds_per_iteration": float(np.median(gaps[iterations:])),
        "iterations_timed": iterations,
        "near_field_pairs": problem.objective.terms[-1].pair_count,
        "peak_memory_mb": peak_memory_mb(),
    }


def design_case(strength, n_points):
    """``stipple design -t T`` with its defaults (both cores): seconds and iterations to largest error 1e-10."""
    stamps = []
    started = time.perf_counter()
    result = spherical_design(strength, n_points, callback=lambda state: stamps.append(time.perf_counter()))
    return {
        "case": f"sphere design t={strength}",
        "M": len(result.points),
        "N": strength,
        "threads": default_threads(),
        "status": result.status,
        "message": result.message,
        "iterations_to_target": result.iterations,
        "seconds_to_target": time.perf_counter() - started,
        "seconds_per_iteration": float(np.median(np.diff(stamps))),
        "peak_memory_mb": peak_memory_mb(),
    }


def main(argv):
    reuse_freed_memory()  # as the command line does
    kind, *values = argv
    if kind == "torus":
        report = torus_case(*map(int, values))
    else:
        report = design_case(int(values[0]), None if values[1] == "default" else int(values[1]))
    print(json.dumps(report))


if __name__ == "__main__":
    main(sys.argv[1:])
