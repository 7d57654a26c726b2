"""Where a whole ``stipple torus`` command's time goes: wall clocks around the transforms, the discrepancy's mode-grid
arithmetic, the near field's pair search and pair sums, and the rest (CG, the start, the finishing steps).

    python bench/phases.py IMAGE -M 200000 [--backend cufinufft] [--threads 1] [--output phases.json]

Run with ``--threads 1``: every phase then runs on the main thread, one after the other, so the clocks add up
(with more threads the transforms and the pairs overlap and the phases' sums exceed the wall time). The
transforms' clock includes the copies to and from the GPU for ``cufinufft``. The grid arithmetic is the
discrepancy's own time less the transforms it makes; the rest is the command less the discrepancy and the pairs.
"""

import argparse
import functools
import json
import sys
import tempfile
import threading
import time
from collections import defaultdict
from pathlib import Path

from stipple import allocator

CLOCKS = defaultdict(float)
CALLS = defaultdict(int)
DEPTH = defaultdict(int)
LOCK = threading.Lock()


def clocked(owner, name, label, patch=setattr):
    """Wrap ``owner.name`` so that its wall time adds to ``CLOCKS[label]``, counting only the outermost of the
    label's calls in progress in any thread (a wrapped transform that hands its residue classes to other
    threads, each a wrapped transform too, counts once)."""
    method = getattr(owner, name)

    @functools.wraps(method)
    def wrapper(*args, **kwargs):
        with LOCK:
            DEPTH[label] += 1
            outermost = DEPTH[label] == 1
        start = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            with LOCK:
                DEPTH[label] -= 1
                if outermost:
                    CLOCKS[label] += time.perf_counter() - start
                    CALLS[label] += 1

    patch(owner, name, wrapper)


def install(patch=setattr):
    """Clocks around the transforms, the discrepancy's and the near field's methods (``patch``: how to replace a
    method, e.g. pytest's ``monkeypatch.setattr``, which undoes it)."""
    from stipple import nearfield, nufft, objective

    transforms = [nufft.Ducc0Nufft, nufft.FinufftNufft, nufft.ResidueSplitNufft]
    try:
        from stipple import gpu

        transforms.append(gpu.CufinufftNufft)
    except ImportError:
        pass
    for owner in transforms:
        for name in ("set_points", "type1", "type2"):
            if hasattr(owner, name):
                clocked(owner, name, "transforms", patch)
    for name in ("set_points", "energy", "gradient", "hessian_gram", "hessian_vectors"):
        clocked(objective.Discrepancy, name, "discrepancy", patch)
        clocked(nearfield.NearField, name, "pairs", patch)
    clocked(nearfield.NearField, "_search", "pair_search", patch)
    clocked(nearfield.NearField, "_update_candidates", "pair_candidates", patch)


def measure(image, count, backend="ducc0", threads=1, patch=setattr):
    """``stipple torus IMAGE -M count`` in this process with the clocks installed: its phases' seconds (see the
    module docstring), the clocks' outermost calls, and the pair list's full searches."""
    for table in (CLOCKS, CALLS, DEPTH):
        table.clear()
    install(patch)
    from stipple.cli.main import main as cli

    with tempfile.TemporaryDirectory() as folder:
        command = ["torus", str(image), "-M", str(count), "--backend", backend, "--threads", str(threads)]
        command += ["-o", str(Path(folder) / "dots.csv"), "--quiet"]
        start = time.perf_counter()
        cli.main(command, standalone_mode=False)
        total = time.perf_counter() - start
    # The transforms run inside the discrepancy's methods; the pair search inside the pairs' set_points.
    phases = {
        "command": total,
        "transforms": CLOCKS["transforms"],
        "grid_arithmetic": CLOCKS["discrepancy"] - CLOCKS["transforms"],
        "pair_search": CLOCKS["pair_candidates"],
        "pair_sums": CLOCKS["pairs"] - CLOCKS["pair_candidates"],
        "rest": total - CLOCKS["discrepancy"] - CLOCKS["pairs"],
    }
    record = {"image": str(image), "M": count, "backend": backend, "threads": threads, "seconds": phases}
    return record | {"calls": dict(CALLS), "full_searches": CALLS["pair_search"]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("image")
    parser.add_argument("-M", type=int, required=True)
    parser.add_argument("--backend", default="ducc0")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--output")
    args = parser.parse_args()
    # What the command line does first (its ``main`` does not when called with ``standalone_mode=False``): big
    # mode-grid arrays then reuse freed memory instead of faulting in new pages at each evaluation.
    allocator.reuse_freed_memory()
    record = measure(args.image, args.M, args.backend, args.threads)
    line = "  ".join(f"{name} {value:.2f}" for name, value in record["seconds"].items())
    print(f"{args.backend} threads {args.threads} M {args.M}: {line} (s; full searches {record['full_searches']})")
    if args.output:
        Path(args.output).write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    sys.exit(main())
