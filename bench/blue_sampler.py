"""blue_sampler's image stippling, for the side-by-side of docs/performance.md (issue 34, point 4).

blue_sampler (PyPI ``blue-sampler``) needs Python >= 3.12, so it runs in its own environment:

    python3.12 -m venv /tmp/bs && /tmp/bs/bin/pip install blue-sampler pillow
    /tmp/bs/bin/python bench/blue_sampler.py IMAGE M dots.csv
    stipple evaluate dots.csv IMAGE          # the same measures as for stipple's own CSV

It times ``blue_sampler.sample_points(N=M, D=2, targets=IMAGE)`` (its default method for an image target, as its
``im2points`` calls it, without the plot) and writes the points as stipple's torus CSV: ``x,y`` in pixels, y down
(blue_sampler's y points up: checked on an image dark only in its top-left eighth, where all its points fell).
"""

import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image


def import_blue_sampler():
    """The package, not this script: Python puts the script's folder first on the path, and its name is the same."""
    here = Path(__file__).resolve().parent
    sys.path[:] = [entry for entry in sys.path if Path(entry or ".").resolve() != here]
    import blue_sampler

    return blue_sampler


def main(image, count, output):
    blue_sampler = import_blue_sampler()

    width, height = Image.open(image).size
    started = time.perf_counter()
    points = blue_sampler.sample_points(N=count, D=2, targets=image, verbose=0)
    seconds = time.perf_counter() - started
    columns, rows = np.mod(points[:, 0] * width, width), np.mod((1 - points[:, 1]) * height, height)
    np.savetxt(output, np.column_stack([columns, rows]), delimiter=",", header="x,y", comments="", fmt="%.6f")
    print(f"{image}: {count} points in {seconds:.1f} s (sample_points only)")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3])
