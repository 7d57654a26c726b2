"""Stroke legibility of a drawn document: contrast-to-noise ratio between strokes and paper after a blur.

strokes: the input's darkest 6 % of pixels; paper: pixels between its 30th and 90th percentiles. CNR =
(mean drawn paper - mean drawn strokes) / std of drawn paper, after a Gaussian blur of sigma input pixels.

    python bench/legibility.py INPUT PICTURE.png [PICTURE.png ...]
"""

import sys

import numpy as np
from PIL import Image
from scipy.ndimage import gaussian_filter


def cnr(inp, drawn, sigma):
    t = np.asarray(Image.open(inp).convert("L"), float) / 255
    d = Image.open(drawn).convert("L").resize(t.shape[::-1], Image.BOX)
    d = gaussian_filter(np.asarray(d, float) / 255, sigma)
    lo, p30, p90 = np.percentile(t, [6, 30, 90])
    strokes, paper = t <= lo, (t >= p30) & (t <= p90)
    return (d[paper].mean() - d[strokes].mean()) / d[paper].std()


if __name__ == "__main__":
    inp = sys.argv[1]
    for path in sys.argv[2:]:
        print(path, " ".join(f"sigma {s}: CNR {cnr(inp, path, s):.2f}" for s in (1, 2)))
