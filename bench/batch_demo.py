"""The ``stipple batch`` cluster demonstration of docs/batch.md, in one command with JSON out.

    python bench/batch_demo.py [--points 3000] [--port 8799] [--work /tmp/stipple-batch-demo] > demo.json

Starts ``dask scheduler`` and two ``dask worker`` processes (``--nthreads 1 --no-nanny``) on localhost, then:

1. ``same``: ``stipple batch --scheduler`` writes byte-identical files to ``stipple torus`` run one by one;
2. ``rescheduled``: ``kill -9`` of one worker mid-batch; the scheduler reruns its task on the other worker and no
   finished file changes;
3. ``rerun``: the same with the scheduler's ``allowed-failures`` at 0, so the killed worker's tasks fail (exit
   100 + failed); a rerun skips the finished images and completes the rest, all identical to torus.

Every dask process is stopped at the end, whatever happens.
"""

import argparse
import filecmp
import json
import os
import shutil
import signal
import subprocess
import sys
import time

IMAGES = [
    "samples/astronaut256.png",
    "samples/camera128.png",
    "/work/heldout/chelsea.png",
    "/work/heldout/coffee300.png",
    "/work/heldout/horse.png",
    "/work/heldout/rocket.png",
]
FORMATS = ("csv", "png", "svg")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=3000)
    parser.add_argument("--port", type=int, default=8799)
    parser.add_argument("--work", default="/tmp/stipple-batch-demo")
    args = parser.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(os.path.join(args.work, "in"))
    images = []
    for path in IMAGES:
        if os.path.exists(path):
            images.append(shutil.copy(path, os.path.join(args.work, "in")))
    options = ["-M", str(args.points), "--threads", "1", "--seed", "0", "--format", ",".join(FORMATS)]
    report = {"points": args.points, "images": [os.path.basename(path) for path in images], "load": load()}
    reference = torus_reference(images, options, os.path.join(args.work, "torus"))
    address = f"tcp://127.0.0.1:{args.port}"
    for name, allowed_failures in (("same", None), ("rescheduled", None), ("rerun", 0)):
        with Cluster(args.port, args.work, allowed_failures) as cluster:
            out = os.path.join(args.work, name)
            command = [*stipple("batch"), *images, "-d", out, *options, "-q", "--scheduler", address]
            if name == "same":
                report[name] = timed(command) | {"identical": identical(reference, out)}
                continue
            report[name] = kill_one_worker_mid_batch(command, cluster, out)
            if name == "rerun":
                before = listing(out)
                report[name]["rerun"] = timed(command) | {"unchanged": unchanged(before, listing(out))}
            report[name]["identical"] = identical(reference, out)
    report["load_after"] = load()
    json.dump(report, sys.stdout, indent=1)
    print()


def stipple(command):
    return [sys.executable, "-m", "stipple", command]


def load():
    return os.getloadavg()[0]


def timed(command):
    started = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True)
    return {"exit": result.returncode, "seconds": round(time.perf_counter() - started, 2), "stderr": result.stderr}


def torus_reference(images, options, folder):
    """``stipple torus`` of each image alone, with the batch's options: {file name: path}."""
    os.makedirs(folder)
    run_options = [option for option in options if option not in ("--format", ",".join(FORMATS))]
    files = {}
    for image in images:
        stem = os.path.splitext(os.path.basename(image))[0]
        outputs = [os.path.join(folder, f"{stem}.{fmt}") for fmt in FORMATS]
        command = [*stipple("torus"), image, *run_options, "-q", *[a for path in outputs for a in ("-o", path)]]
        subprocess.run(command, check=True)
        files.update({os.path.basename(path): path for path in outputs})
    return files


def identical(reference, folder):
    """Whether every reference file has a byte-identical twin in ``folder``, and nothing else is there."""
    names = sorted(os.listdir(folder))
    same = names == sorted(reference) and all(
        filecmp.cmp(reference[name], os.path.join(folder, name), shallow=False) for name in names
    )
    return {"files": len(names), "all_identical": same}


def listing(folder):
    """{name: mtime in ns} of every file of ``folder`` (temporaries included)."""
    if not os.path.isdir(folder):
        return {}
    return {name: os.stat(os.path.join(folder, name)).st_mtime_ns for name in sorted(os.listdir(folder))}


def unchanged(before, after):
    return sorted(name for name in before if after.get(name) == before[name])


def kill_one_worker_mid_batch(command, cluster, out):
    """Start the batch, ``kill -9`` worker 1 one second after the first image's files appear, and report."""
    started = time.perf_counter()
    batch = subprocess.Popen(command, stderr=subprocess.PIPE, text=True)
    while not any(name.endswith(".svg") for name in listing(out)) and batch.poll() is None:
        time.sleep(0.05)
    time.sleep(1.0)
    cluster.kill_worker(0)
    at_kill = listing(out)
    _, stderr = batch.communicate()
    after = listing(out)
    return {
        "exit": batch.returncode,
        "seconds": round(time.perf_counter() - started, 2),
        "stderr": stderr,
        "files_at_kill": sorted(at_kill),
        "finished_at_kill_unchanged": unchanged(at_kill, after) == sorted(at_kill),
        "files_after": len(after),
        "temporaries_after": [name for name in after if name.endswith(".tmp")],
    }


class Cluster:
    """``dask scheduler`` and two ``dask worker`` processes on localhost, stopped on leaving the block."""

    def __init__(self, port, work, allowed_failures=None):
        self.port, self.work, self.allowed_failures = port, work, allowed_failures
        self.processes = []

    def __enter__(self):
        environment = dict(os.environ)
        if self.allowed_failures is not None:
            environment["DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES"] = str(self.allowed_failures)
        address = f"tcp://127.0.0.1:{self.port}"
        scheduler = ["dask", "scheduler", "--host", "127.0.0.1", "--port", str(self.port), "--no-dashboard"]
        worker = ["dask", "worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard"]
        log = open(os.path.join(self.work, "dask.log"), "a")
        self.processes.append(subprocess.Popen(scheduler, stdout=log, stderr=log, env=environment))
        time.sleep(3)
        for index in range(2):
            self.processes.append(subprocess.Popen([*worker, "--name", f"w{index + 1}"], stdout=log, stderr=log))
        time.sleep(4)
        return self

    def kill_worker(self, index):
        self.processes[1 + index].send_signal(signal.SIGKILL)

    def __exit__(self, *exc):
        for process in reversed(self.processes):
            if process.poll() is None:
                process.terminate()
        for process in self.processes:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


if __name__ == "__main__":
    main()
