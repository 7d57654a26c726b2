"""Issue 33's sweep: small careless and hostile cases over all nine commands, each checked for the guarantees.

Every case runs ``stipple`` in a fresh process with a 60 s limit in a scratch folder and is classed:

- ``ok`` cases must exit 0 and write whole outputs (a CSV with the right number of rows, a PNG that decodes);
- ``refused`` cases must exit non-zero with one line on stderr and no traceback;
- every case must leave the inputs and any pre-existing outputs byte for byte and no temporary file behind.

A case that breaks one of these is a defect; the script prints one line per defect and the counts::

    .venv/bin/python bench/hostile_sweep.py            # about 3 minutes on 2 cores

Nothing here opens a network connection except to 127.0.0.1 (an unused port, for the refused-scheduler case).
"""

import csv
import io
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

LIMIT = 60
QUICK = ["--iterations", "2", "-q", "--seed", "1"]


def make_inputs(folder):
    """The sweep's input files in ``folder``."""
    ramp = np.tile(np.linspace(0, 250, 48).round().astype(np.uint8), (32, 1))
    Image.fromarray(ramp).save(folder / "grad.png")
    Image.fromarray(ramp.astype(np.uint16) * 257).save(folder / "g16.png")
    Image.fromarray((ramp / 255).astype(np.float32)).save(folder / "float.tiff")
    Image.fromarray(np.dstack([ramp, 255 - ramp, ramp // 2])).save(folder / "colour.png")
    Image.fromarray(np.dstack([ramp, ramp, ramp, ramp])).save(folder / "rgba.png")
    Image.fromarray(ramp).convert("P").save(folder / "palette.png")
    Image.fromarray(np.full((16, 16), 255, np.uint8)).save(folder / "white.png")
    Image.fromarray(np.zeros((16, 16), np.uint8)).save(folder / "black.png")
    Image.fromarray(np.full((16, 16), 128, np.uint8)).save(folder / "flat.png")
    Image.fromarray(ramp[:1, :1]).save(folder / "tiny.png")
    np.save(folder / "map.npy", np.outer(np.linspace(1, 2, 16), np.ones(32)))
    np.save(folder / "nan.npy", np.full((8, 8), np.nan))
    np.save(folder / "objects.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    (folder / "empty.png").write_bytes(b"")
    (folder / "truncated.png").write_bytes((folder / "grad.png").read_bytes()[:60])
    (folder / "text.png").write_text("not an image\n")
    (folder / "frames").mkdir()
    for index in range(3):
        Image.fromarray(np.roll(ramp, index, axis=1)).save(folder / "frames" / f"{index}.png")
    (folder / "blank_frames").mkdir()
    for index, picture in enumerate([ramp, np.full_like(ramp, 255)]):
        Image.fromarray(picture).save(folder / "blank_frames" / f"{index}.png")
    (folder / "keep.csv").write_text("precious\n")
    (folder / "readonly.csv").write_text("precious\n")
    (folder / "readonly.csv").chmod(0o444)
    (folder / "rodir").mkdir()
    (folder / "rodir").chmod(0o555)
    (folder / "out").mkdir()
    (folder / "vf").mkdir()
    (folder / "bad.toml").write_text("points = [[[\n")
    (folder / "unknown.toml").write_text("nosuch = 3\n")
    subprocess.run(
        [sys.executable, "-m", "stipple", "torus", "grad.png", "-M", "60", "-N", "12", *QUICK, "-o", "dots.csv"],
        cwd=folder,
        check=True,
        timeout=LIMIT,
    )
    Image.open(folder / "grad.png").convert("RGB").save(folder / "drawn.png")
    (folder / "bad_points.csv").write_text("x,y\n1,nan\n2,3\n")
    # A million copies of one point (5 million kept render busy for over 10 minutes before they were one point).
    (folder / "copies.csv").write_text("x,y\n" + "3,4\n" * 1_000_000 + "5,6\n")
    (folder / "one_point.csv").write_text("x,y\n1,2\n")


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def cases():
    """``(expect, args, outputs)``: "ok", "refused" or "not a design" (written, exit 3), the command's arguments,
    the output files to check."""
    ok, no, short = "ok", "refused", "not a design"
    small = ["-M", "60", "-N", "12", *QUICK]
    yield from [
        # torus: formats, storages, options
        *[
            (ok, ["torus", name, *small, "-o", "o.csv"], ["o.csv"])
            for name in (
                "grad.png",
                "g16.png",
                "float.tiff",
                "colour.png",
                "rgba.png",
                "palette.png",
                "map.npy",
                "flat.png",
            )
        ],
        (ok, ["torus", "grad.png", *small, "-o", "o.png", "-o", "o.svg"], ["o.png", "o.svg"]),
        (ok, ["torus", "g16.png", *small, "--palette", "cmyk", "-o", "o.csv"], ["o.csv"]),
        (ok, ["torus", "float.tiff", *small, "--palette", "cmyk", "-o", "o.csv"], ["o.csv"]),
        (ok, ["torus", "grad.png", *small, "--levels", "auto", "-o", "o.csv"], ["o.csv"]),
        (ok, ["torus", "grad.png", *small, "--order", "-o", "o.svg"], ["o.svg"]),
        (ok, ["torus", "grad.png", *small, "--invert", "-o", "o.png"], ["o.png"]),
        *[
            (no, ["torus", name, *small, "-o", "o.csv"], [])
            for name in (
                "white.png",
                "empty.png",
                "truncated.png",
                "text.png",
                "nan.npy",
                "objects.npy",
                "tiny.png",
                "missing.png",
                "frames",
            )
        ],
        *[
            (no, ["torus", "grad.png", *small, *extra, "-o", "o.csv"], [])
            for extra in (
                ["-M", "0"],
                ["-M", "-5"],
                ["-N", "3"],
                ["-N", "100000"],
                ["--gamma", "0"],
                ["--gamma", "nan"],
                ["--levels", "5,2"],
                ["--levels", "a,b"],
                ["--tol", "-1"],
                ["--epsilon", "1"],
                ["--threads", "0"],
                ["--time-limit", "-1"],
                ["--width", "-3mm"],
                ["--width", "10parsecs"],
                ["--color", "nosuch"],
                ["--png-width", "5"],
                ["--init", "missing.csv"],
                ["--checkpoint-every", "0"],
                ["--range", "2", "1"],
                ["--seed", "-1"],
                ["--palette", "nosuch"],
                ["--resume"],
            )
        ],
        (no, ["torus", "black.png", *small, "--invert", "-o", "o.csv"], []),
        (no, ["torus", "flat.png", *small, "--levels", "auto", "-o", "o.csv"], []),
        (no, ["torus", "grad.png", *small, "-o", "readonly.csv"], []),
        (no, ["torus", "grad.png", *small, "-o", "rodir/o.csv"], []),
        (no, ["torus", "grad.png", *small, "-o", "grad.png"], []),
        (no, ["torus", "grad.png", *small, "-o", "o.jpg"], []),
        (no, ["torus", "grad.png", *small, "-o", "nodir/o.csv"], []),
        (no, ["torus", "grad.png", *small, "-o", "-", "-o", "-"], []),
        (no, ["torus", "--config", "bad.toml", *small, "-o", "o.csv"], []),
        (no, ["torus", "--config", "unknown.toml", "grad.png", *small, "-o", "o.csv"], []),
        (no, ["torus", *small, "-o", "o.csv"], []),
        # colour
        (ok, ["colour", "colour.png", *small, "-o", "o.csv"], ["o.csv"]),
        (ok, ["colour", "g16.png", *small, "-o", "o.csv", "-o", "o.svg"], ["o.csv", "o.svg"]),
        (ok, ["colour", "float.tiff", *small, "-o", "o.png"], ["o.png"]),
        (ok, ["colour", "palette.png", *small, "--palette", "#ff0000,black", "-o", "o.csv"], ["o.csv"]),
        *[(no, ["colour", name, *small, "-o", "o.csv"], []) for name in ("white.png", "map.npy", "empty.png")],
        *[
            (no, ["colour", "colour.png", *small, *extra, "-o", "o.csv"], [])
            for extra in (
                ["--palette", "nosuch"],
                ["--invert"],
                ["--gamma", "2"],
                ["--levels", "auto"],
                ["--black", "2"],
                ["--color", "red"],
                ["-M", "0"],
            )
        ],
        # batch
        (ok, ["batch", "grad.png", "g16.png", *small, "--format", "csv", "-d", "b1"], ["b1/grad.csv", "b1/g16.csv"]),
        (ok, ["batch", "frames/*.png", *small, "--format", "csv,png", "-d", "b2"], ["b2/0.csv", "b2/2.png"]),
        (ok, ["batch", "float.tiff", *small, "--format", "svg", "-d", "out"], ["out/float.svg"]),
        *[
            (no, ["batch", "grad.png", "g16.png", *small, *extra, "-d", "bx"], [])
            for extra in (
                ["-M", "0"],
                ["--levels", "5,2"],
                ["-N", "3"],
                ["--gamma", "-1"],
                ["--format", "jpg"],
                ["--init", "dots.csv"],
                ["--scheduler", "tcp://127.0.0.1:99999"],
                ["--scheduler", ""],
                ["--scheduler", "http://127.0.0.1:80"],
                ["--scheduler", f"tcp://127.0.0.1:{free_port()}"],
                ["--tol", "0"],
                ["--seed", "-3"],
                ["--epsilon", "5"],
            )
        ],
        (no, ["batch", "grad.png", *small, "-d", "rodir"], []),
        (no, ["batch", "grad.png", *small, "-d", "keep.csv"], []),
        (no, ["batch", "nomatch*.png", *small, "-d", "bx"], []),
        (no, ["batch", "-", *small, "-d", "bx"], []),
        (no, ["batch", "frames", *small, "-d", "bx"], []),
        # The same file under two names is one job (2026-11-27; it was refused as a clash of names).
        (ok, ["batch", "grad.png", "frames/../grad.png", *small, "--format", "csv", "-d", "bx"], ["bx/grad.csv"]),
        (ok, ["batch", "grad.png", *small, "--format", "csv", "-d", "."], ["grad.csv"]),
        # line
        (ok, ["line", "grad.png", "-M", "120", *QUICK, "-o", "o.csv"], ["o.csv"]),
        (ok, ["line", "g16.png", "-M", "120", *QUICK, "-o", "o.svg", "-o", "o.png"], ["o.svg", "o.png"]),
        (ok, ["line", "grad.png", "-M", "120", *QUICK, "--length", "400", "-N", "24", "-o", "o.csv"], ["o.csv"]),
        *[
            (no, ["line", "grad.png", "-M", "120", *QUICK, *extra, "-o", "o.csv"], [])
            for extra in (
                ["--length", "1"],
                ["--length", "3"],
                ["--length", "1e12"],
                ["--length", "-5"],
                ["--length", "inf"],
                ["-N", "100000"],
                ["-N", "3"],
                ["-M", "3"],
                ["-M", "0"],
                ["--init", "missing.csv"],
                ["--epsilon", "0"],
                ["--gamma", "0"],
            )
        ],
        (no, ["line", "white.png", "-M", "120", *QUICK, "-o", "o.csv"], []),
        (no, ["line", "grad.png", "-M", "120", *QUICK, "-o", "o.geojson"], []),
        # video
        (ok, ["video", "frames", *small, "-o", "v.csv"], ["v.csv"]),
        (ok, ["video", "frames/*.png", *small, "-o", "vf/%02d.png"], ["vf/00.png", "vf/02.png"]),
        (ok, ["video", "frames", *small, "-o", "vf/100%%_%d.svg"], ["vf/100%_1.svg"]),
        (ok, ["video", "frames", *small, "--palette", "cmyk", "-o", "v.csv"], ["v.csv"]),
        *[
            (no, ["video", source, *small, "-o", "v.csv"], [])
            for source in (
                "blank_frames",
                "out",
                "nomatch*.png",
                "grad.png",
                "missing",
            )
        ],
        *[
            (no, ["video", "frames", *small, *extra], [])
            for extra in (
                ["-o", "vf/frame.png"],
                ["-o", "vf/%d_%d.png"],
                ["-o", "v.gif"],
                ["-o", "v.csv", "-M", "0"],
                ["-o", "v.csv", "--levels", "9,1"],
                ["-o", "v.csv", "-N", "5"],
                ["-o", "readonly.csv"],
            )
        ],
        # evaluate
        (ok, ["evaluate", "dots.csv", "grad.png"], []),
        (ok, ["evaluate", "dots.csv", "g16.png"], []),
        (ok, ["evaluate", "dots.csv", "float.tiff", "--json", "r.json"], ["r.json"]),
        (ok, ["evaluate", "drawn.png", "grad.png", "--sigma", "2"], []),
        (ok, ["evaluate", "drawn.png", "g16.png", "--gray", "--levels", "auto"], []),
        (ok, ["evaluate", "dots.csv", "grad.png", "--levels", "auto"], []),
        (ok, ["evaluate", "drawn.png", "palette.png"], []),
        *[
            (no, ["evaluate", *args], [])
            for args in (
                ["dots.csv", "builtin:nosuch"],
                ["dots.csv", "grad.png", "--sigma", "2"],
                ["dots.csv", "grad.png", "--inset", "3"],
                ["drawn.png", "grad.png", "--line"],
                ["drawn.png", "grad.png", "--sigma", "1e9"],
                ["drawn.png", "grad.png", "--sigma", "0"],
                ["bad_points.csv", "grad.png"],
                ["one_point.csv", "grad.png"],
                ["missing.csv", "grad.png"],
                ["dots.csv", "missing.png"],
                ["dots.csv", "empty.png"],
                ["drawn.png", "grad.png", "--spectrum", "s.png"],
                ["dots.csv", "grad.png", "--json", "r.txt"],
                ["dots.csv", "grad.png", "--json", "readonly.csv"],
                ["drawn.png"],
                ["dots.csv", "grad.png", "-N", "3"],
            )
        ],
        # sphere
        (ok, ["sphere", "map.npy", "-M", "80", *QUICK, "-o", "s.csv"], ["s.csv"]),
        (ok, ["sphere", "grad.png", "-M", "80", *QUICK, "-o", "s.geojson"], ["s.geojson"]),
        (ok, ["sphere", "--uniform", "-M", "80", *QUICK, "-o", "s.png"], ["s.png"]),
        (ok, ["sphere", "builtin:rbf", "-M", "80", *QUICK, "-o", "s.csv"], ["s.csv"]),
        *[
            (no, ["sphere", *args, *QUICK, "-o", "s.csv"], [])
            for args in (
                ["builtin:nosuch", "-M", "80"],
                ["map.npy", "-M", "0"],
                ["nan.npy", "-M", "80"],
                ["objects.npy", "-M", "80"],
                ["map.npy", "--uniform", "-M", "80"],
                ["map.npy", "-M", "80", "-N", "-2"],
                ["map.npy", "-M", "80", "--range", "1", "1"],
                ["empty.png", "-M", "80"],
                ["white.png", "-M", "80"],
                ["map.npy", "-M", "80", "--view", "0,100"],
            )
        ],
        # design
        (short, ["design", "-t", "3", *QUICK, "-o", "d.csv"], ["d.csv"]),
        (short, ["design", "-t", "4", "-M", "20", *QUICK, "-o", "d.csv"], ["d.csv"]),
        *[
            (no, ["design", *args, *QUICK, "-o", "d.csv"], [])
            for args in (
                ["-t", "0"],
                ["-t", "-1"],
                ["-t", "100000"],
                ["-t", "3", "-M", "1"],
                ["-t", "3", "--error", "-1"],
                ["-t", "3", "--init", "nosuch"],
                ["-t", "3", "--error", "nan"],
            )
        ],
        # render
        (ok, ["render", "dots.csv", "-o", "r.png"], ["r.png"]),
        (ok, ["render", "dots.csv", "-o", "r.svg", "--dot-style", "circle"], ["r.svg"]),
        (ok, ["render", "copies.csv", "-o", "r.svg", "--dot-style", "circle"], ["r.svg"]),
        *[
            (no, ["render", *args], [])
            for args in (
                ["missing.csv", "-o", "r.png"],
                ["bad_points.csv", "-o", "r.png"],
                ["grad.png", "-o", "r.png"],
                ["dots.csv", "-o", "r.jpg"],
                ["dots.csv", "-o", "dots.csv"],
                ["dots.csv", "-o", "r.png", "--png-width", "1"],
                ["dots.csv", "-o", "r.png", "--width", "0mm"],
                ["dots.csv", "-o", "readonly.csv"],
                ["empty.png", "-o", "r.png"],
            )
        ],
    ]


def snapshot(folder):
    return {
        str(path.relative_to(folder)): path.read_bytes()
        for path in sorted(folder.rglob("*"))
        if path.is_file() and not path.is_symlink()
    }


def rows(path, data):
    """Number of CSV data rows, or None if it is not a readable CSV."""
    try:
        return len(list(csv.reader(io.StringIO(data.decode())))) - 1
    except (UnicodeError, csv.Error):
        return None


def check(expect, args, outputs, folder):
    """The defects of one case (empty if none)."""
    before = snapshot(folder)
    started = time.monotonic()
    try:
        result = subprocess.run(
            [sys.executable, "-m", "stipple", *args], cwd=folder, capture_output=True, text=True, timeout=LIMIT
        )
    except subprocess.TimeoutExpired:
        return [f"hangs (over {LIMIT} s)"]
    seconds = time.monotonic() - started
    defects, after = [], snapshot(folder)
    stderr = result.stderr.strip()
    if "Traceback" in result.stderr + result.stdout:
        defects.append("traceback")
    changed = [name for name, data in before.items() if after.get(name) != data]
    if changed:
        defects.append(f"changed existing files {changed}")
    temporary = [name for name in after if ".stipple-" in name or name.endswith((".tmp", ".lock"))]
    if temporary:
        defects.append(f"left temporary files {temporary}")
    if expect == "refused":
        if result.returncode == 0:
            defects.append("exit 0 on bad input")
        if len(stderr.splitlines()) != 1:
            defects.append(f"{len(stderr.splitlines())} lines on stderr")
        new = sorted(set(after) - set(before))
        if new:
            defects.append(f"wrote {new} although refused")
    else:
        code = 3 if expect == "not a design" else 0
        if result.returncode != code:
            defects.append(f"exit {result.returncode}: {stderr[-200:]}")
        for name in outputs:
            data = after.get(name)
            if not data:
                defects.append(f"no output {name}")
            elif name.endswith(".png"):
                Image.open(io.BytesIO(data)).load()
            elif name.endswith(".csv") and not rows(name, data):
                defects.append(f"{name} has no rows")
    if seconds > 30:
        defects.append(f"slow ({seconds:.0f} s)")
    return defects


def reset(folder, pristine):
    """Remove what the last case wrote (outputs are compared against the pristine inputs)."""
    for path in sorted(folder.rglob("*"), reverse=True):
        name = str(path.relative_to(folder))
        if path.is_file() and name not in pristine:
            path.unlink()
        elif path.is_dir() and not any(path.iterdir()) and name not in ("out", "rodir", "vf"):
            path.rmdir()


def main():
    folder = Path(tempfile.mkdtemp(prefix="stipple-sweep-"))
    try:
        make_inputs(folder)
        pristine = snapshot(folder)
        all_cases = list(cases())
        found = 0
        per_command = {}
        for expect, args, outputs in all_cases:
            defects = check(expect, [str(arg) for arg in args], outputs, folder)
            per_command.setdefault(args[0], [0, 0])[0] += 1
            if defects:
                found += 1
                per_command[args[0]][1] += 1
                print(f"DEFECT {expect}: stipple {' '.join(map(str, args))}: {'; '.join(defects)}", flush=True)
            reset(folder, pristine)
        print(f"{len(all_cases)} cases, {found} with a defect; per command (cases, defects): {per_command}")
        return 1 if found else 0
    finally:
        (folder / "rodir").chmod(0o755)
        (folder / "readonly.csv").chmod(0o644)
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    sys.exit(main())
