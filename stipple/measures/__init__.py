"""How well a drawing reproduces its input: the measures of ``stipple evaluate`` and of the benchmarks.

Modules: ``evaluate`` (measures of point sets: ``E_N`` against i.i.d. samples, exact-blur PSNR and SSIM,
clumps, the power spectrum, a line's ink), ``picture`` (measures of a drawn PNG against its input, both blurred
at viewing distance: luminance RMSE and the tone curve, or CIEDE2000 and chroma; Floyd-Steinberg for reference),
``reports`` (the reports ``stipple evaluate`` prints: which measures for which file, read from the inputs),
``plot_estimate`` (a drawing's plot per pen: lengths, lifts and time; ``stipple evaluate DRAWING.svg``).
"""

from .evaluate import evaluate_line, evaluate_sphere, evaluate_torus, image_similarity
from .picture import measure_picture
from .reports import evaluation_report, picture_report

__all__ = [
    "evaluate_line",
    "evaluate_sphere",
    "evaluate_torus",
    "evaluation_report",
    "image_similarity",
    "measure_picture",
    "picture_report",
]
