"""Picture measures: how a drawn picture reproduces its input's tone and colour, as a viewer sees it from afar.

Both pictures are brought to the input's pixel grid (the drawing by area averaging) and blurred by a Gaussian of
``sigma`` input pixels (``mode="reflect"``: a picture's edges are not periodic, even when its dots were placed
on the torus). Gray: the luminance RMSE and the tone curve (input pixels sorted into tenths of blurred input
luminance; the mean blurred input and drawn luminance per tenth). Colour: both pictures' sRGB values are blurred
and compared in CIELAB (scikit-image, D65): the mean and 95th percentile of CIEDE2000, the drawn chroma over the
input's, the mean L* difference. ``floyd_steinberg`` draws the baseline a user would otherwise pick: error
diffusion with about as many square dots.
"""

from dataclasses import asdict, dataclass

import numpy as np
from PIL import Image
from scipy import sparse
from scipy.ndimage import gaussian_filter

from ..io.images import LUMA

SIGMAS = (2.0, 4.0)
TENTHS = 10
# The eight corners of the RGB cube: the inks (and white paper) of the colour Floyd-Steinberg baseline.
CUBE = [(r, g, b) for r in (0, 255) for g in (0, 255) for b in (0, 255)]
# The worst tenth is taken over tenths holding at least this share of the pixels: a tenth of a few pixels (a
# blurred cut frame's darkest 1 pixel of 19200) measured one pixel's noise, not a tone.
WORST_TENTH_SHARE = 1e-3


@dataclass(frozen=True)
class ToneBin:
    """One tenth of the tone curve: input pixels whose blurred luminance is in ``[low, high)``."""

    low: float
    high: float
    pixels: int
    input: float
    output: float


@dataclass(frozen=True)
class GrayMeasures:
    """Luminance measures at one blur ``sigma`` (input pixels); ``worst_tenth`` is the largest |output - input|
    over the tone curve's tenths that hold at least ``WORST_TENTH_SHARE`` of the pixels."""

    sigma: float
    rmse: float
    mean_difference: float
    worst_tenth: float
    tone_curve: tuple

    def as_dict(self):
        return asdict(self)


@dataclass(frozen=True)
class ColourMeasures:
    """CIELAB measures at one blur ``sigma`` (input pixels)."""

    sigma: float
    delta_e00: float
    delta_e00_p95: float
    chroma_ratio: float | None
    mean_L_difference: float
    luminance_rmse: float

    def as_dict(self):
        return asdict(self)


def on_grid(picture, shape, inset=0.0):
    """A picture area-averaged onto a grid.

    Parameters
    ----------
    picture : numpy.ndarray
        Values in [0, 1], ``(rows, columns)`` or ``(rows, columns, channels)``.
    shape : (int, int)
        The grid's ``(rows, columns)``: the input's.
    inset : float
        Input pixels: the picture's region ``[inset, columns - inset] x [inset, rows - inset]`` is taken as the
        input's whole area (a plotter-style drawing maps the torus onto the canvas shrunk by its largest dot
        radius; this undoes that map). 0 measures the picture as drawn.

    Returns
    -------
    numpy.ndarray
        ``(rows, columns)`` or ``(rows, columns, channels)`` float64 in [0, 1].
    """
    rows, columns = shape
    if np.shape(picture)[:2] == (rows, columns) and inset == 0:
        return np.clip(np.asarray(picture, dtype=np.float64), 0.0, 1.0)
    if not 0 <= inset < min(rows, columns) / 2:
        raise ValueError(f"inset must be in [0, {min(rows, columns) / 2:g}) input pixels, not {inset}")
    return area_average(picture, shape, (inset / rows, inset / columns))


def luminance(rgb):
    """Rec. 601 luma of sRGB values ``(..., 3)``."""
    return np.asarray(rgb, dtype=np.float64) @ LUMA


def blur(values, sigma):
    """Gaussian blur of ``sigma`` pixels along the two image axes (``mode="reflect"``), channels apart."""
    sigmas = (sigma, sigma) + (0,) * (np.ndim(values) - 2)
    return gaussian_filter(np.asarray(values, dtype=np.float64), sigmas, mode="reflect")


def tone_curve(reference, picture):
    """The tone curve of blurred luminances: a ``ToneBin`` per non-empty tenth of ``reference``."""
    tenth = np.clip(np.floor(reference * TENTHS).astype(int), 0, TENTHS - 1)
    curve = []
    for k in range(TENTHS):
        chosen = tenth == k
        if chosen.any():
            low, high = k / TENTHS, (k + 1) / TENTHS
            curve.append(ToneBin(low, high, int(chosen.sum()), reference[chosen].mean(), picture[chosen].mean()))
    return tuple(curve)


def gray_measures(reference, picture, sigma):
    """``GrayMeasures`` of ``picture`` against ``reference`` (luminances ``(H, W)`` in [0, 1]) blurred by
    ``sigma`` pixels."""
    a, b = blur(reference, sigma), blur(picture, sigma)
    curve = tone_curve(a, b)
    return GrayMeasures(
        sigma=float(sigma),
        rmse=float(np.sqrt(np.mean((a - b) ** 2))),
        mean_difference=float(np.mean(b - a)),
        worst_tenth=_worst_tenth(curve, a.size),
        tone_curve=curve,
    )


def _worst_tenth(curve, pixels):
    """The largest |output - input| of the tenths holding ``WORST_TENTH_SHARE`` of the ``pixels`` (all of them when
    none does)."""
    counted = [row for row in curve if row.pixels >= WORST_TENTH_SHARE * pixels] or curve
    return float(max(abs(row.output - row.input) for row in counted))


# Mean chroma C*ab (blurred) below which an input is neutral: no ratio of chroma is given (a gray input's 0.003
# made a CMY picture's 3.9 at sigma 2 px read "chroma 1255.673 of the input's").
NEUTRAL_CHROMA = 1.0


def colour_measures(reference, picture, sigma):
    """``ColourMeasures`` of ``picture`` against ``reference`` (sRGB ``(H, W, 3)`` in [0, 1]) blurred by
    ``sigma`` pixels (in sRGB values)."""
    from skimage.color import deltaE_ciede2000, rgb2lab

    a, b = np.clip(blur(reference, sigma), 0, 1), np.clip(blur(picture, sigma), 0, 1)
    lab_a, lab_b = rgb2lab(a), rgb2lab(b)
    delta = deltaE_ciede2000(lab_a, lab_b)
    chroma_a = np.hypot(lab_a[..., 1], lab_a[..., 2]).mean()
    chroma_b = np.hypot(lab_b[..., 1], lab_b[..., 2]).mean()
    return ColourMeasures(
        sigma=float(sigma),
        delta_e00=float(delta.mean()),
        delta_e00_p95=float(np.percentile(delta, 95)),
        chroma_ratio=float(chroma_b / chroma_a) if chroma_a >= NEUTRAL_CHROMA else None,
        mean_L_difference=float(np.mean(lab_b[..., 0] - lab_a[..., 0])),
        luminance_rmse=float(np.sqrt(np.mean(luminance(a - b) ** 2))),
    )


def mean_chroma(rgb):
    """Mean CIELAB chroma C*ab of sRGB values ``(H, W, 3)`` in [0, 1] (0 for a gray picture)."""
    from skimage.color import rgb2lab

    lab = rgb2lab(np.clip(rgb, 0, 1))
    return float(np.hypot(lab[..., 1], lab[..., 2]).mean())


def measure_picture(reference, picture, *, sigmas=SIGMAS, inset=0.0):
    """Picture measures of a drawing against its input at each blur.

    Parameters
    ----------
    reference : numpy.ndarray
        The input: luminance ``(H, W)`` (gray measures) or sRGB ``(H, W, 3)`` (colour measures), in [0, 1].
    picture : numpy.ndarray
        The drawing, any size: sRGB ``(rows, columns, 3)`` or luminance ``(rows, columns)`` in [0, 1]; brought to
        the reference's grid by ``on_grid``.
    sigmas : sequence of float
        Blurs in input pixels, each > 0.
    inset : float
        As for ``on_grid``.

    Returns
    -------
    list of GrayMeasures or ColourMeasures
        One per sigma.
    """
    reference, picture = np.asarray(reference, dtype=np.float64), np.asarray(picture, dtype=np.float64)
    if reference.ndim not in (2, 3) or picture.ndim not in (2, 3):
        raise ValueError("reference and picture must be (H, W) luminances or (H, W, 3) sRGB values")
    for name, values in (("reference", reference), ("picture", picture)):
        if not (np.all(np.isfinite(values)) and values.min() >= 0 and values.max() <= 1):
            raise ValueError(f"{name} values must be finite and in [0, 1]")
    if not sigmas or not all(np.isfinite(s) and s > 0 for s in sigmas):
        raise ValueError(f"sigmas must be positive numbers of input pixels, not {tuple(sigmas)}")
    picture = on_grid(picture, reference.shape[:2], inset)
    if reference.ndim == 3:
        picture = picture if picture.ndim == 3 else np.repeat(picture[..., None], 3, axis=2)
        return [colour_measures(reference, picture, s) for s in sigmas]
    picture = luminance(picture) if picture.ndim == 3 else picture
    return [gray_measures(reference, picture, s) for s in sigmas]


def floyd_steinberg(reference, count, light_dots=False):
    """The baseline a user would otherwise pick: Floyd-Steinberg error diffusion with about ``count`` dots.

    The input is scaled (Pillow, Lanczos) so that its dithered version has about ``count`` ink pixels (the scale
    is searched), dithered, and drawn back at the input's size as square dots, each input pixel the exact
    area average of the dithered pixels over it (``area_average``). Gray: black and white (Pillow's
    ``convert("1")``); colour: the eight corners of the RGB cube, ink pixels being the non-white ones. (Until
    2026-11-26 the dots were drawn back through a nearest-neighbour 4x enlargement, which moved their edges by up
    to an eighth of an input pixel: FS measured 0.0055 instead of 0.0038 at sigma 4 px on a line drawing.)

    Parameters
    ----------
    reference : numpy.ndarray
        Luminance ``(H, W)`` or sRGB ``(H, W, 3)`` in [0, 1].
    count : int
        The number of dots, >= 1.
    light_dots : bool
        Gray only: the dots are white on black (``--invert``): the negative is dithered with ``count`` black
        pixels and negated back (the black ones were counted as dots before 2026-11-26, overstating its error).

    Returns
    -------
    picture : numpy.ndarray
        The dithered picture on the reference's grid, the reference's shape.
    dots : int
        The ink pixels it has.
    """
    if count < 1:
        raise ValueError(f"count must be at least 1, not {count}")
    colour = np.ndim(reference) == 3
    if light_dots and not colour:
        negative, dots = floyd_steinberg(1.0 - np.asarray(reference, dtype=np.float64), count)
        return 1.0 - negative, dots
    image = Image.fromarray(np.round(np.clip(reference, 0, 1) * 255).astype(np.uint8), "RGB" if colour else "L")
    dither = _dither_cube if colour else _dither_black
    dithered, dots = _search_scale(image, count, dither)
    return area_average(np.asarray(dithered, dtype=np.float64) / 255.0, np.shape(reference)[:2]), dots


def area_average(picture, shape, inset=(0.0, 0.0)):
    """``picture`` (``(h, w)`` or ``(h, w, channels)``) stretched over a grid of ``shape = (rows, columns)``, each
    grid cell the exact area average of the picture's pixels over it, at any ratio of sizes; ``inset``, the
    shares ``(of the height, of the width)`` cut off each side of the picture first."""
    picture = np.asarray(picture, dtype=np.float64)
    rows_weights = _overlaps(shape[0], picture.shape[0], inset[0])
    columns_weights = _overlaps(shape[1], picture.shape[1], inset[1])
    channels = [picture] if picture.ndim == 2 else [picture[..., k] for k in range(picture.shape[2])]
    averaged = [np.asarray((columns_weights @ (rows_weights @ channel).T).T) for channel in channels]
    return np.clip(averaged[0] if picture.ndim == 2 else np.stack(averaged, axis=-1), 0.0, 1.0)


def _overlaps(cells, pixels, inset=0.0):
    """Sparse ``(cells, pixels)``: the share of each of ``cells`` equal cells of ``[inset, 1 - inset]`` that each of
    ``pixels`` equal pixels of ``[0, 1]`` covers (a cell overlaps a few neighbouring pixels only)."""
    cell_edges, pixel_edges = np.linspace(inset, 1 - inset, cells + 1), np.linspace(0, 1, pixels + 1)
    first = np.clip(np.searchsorted(pixel_edges, cell_edges[:-1], side="right") - 1, 0, pixels - 1)
    last = np.clip(np.searchsorted(pixel_edges, cell_edges[1:], side="left") - 1, 0, pixels - 1)
    counts = last - first + 1
    row = np.repeat(np.arange(cells), counts)
    column = np.concatenate([np.arange(a, b + 1) for a, b in zip(first, last, strict=True)])
    low = np.maximum(cell_edges[:-1][row], pixel_edges[column])
    high = np.minimum(cell_edges[1:][row], pixel_edges[column + 1])
    share = np.clip(high - low, 0.0, None) / (cell_edges[1] - cell_edges[0])
    return sparse.csr_matrix((share, (row, column)), shape=(cells, pixels))


def _dither_black(image):
    """Black-and-white error diffusion: ``(picture "L", black pixels)``."""
    dithered = image.convert("1", dither=Image.Dither.FLOYDSTEINBERG).convert("L")
    return dithered, int(np.count_nonzero(np.asarray(dithered) == 0))


def _dither_cube(image):
    """Error diffusion onto the RGB cube's corners: ``(picture "RGB", non-white pixels)``."""
    palette = Image.new("P", (1, 1))
    palette.putpalette([v for corner in CUBE for v in corner] + [0, 0, 0] * (256 - len(CUBE)))
    dithered = image.quantize(palette=palette, dither=Image.Dither.FLOYDSTEINBERG).convert("RGB")
    return dithered, int(np.count_nonzero(np.any(np.asarray(dithered) < 255, axis=2)))


# The most pixels a Floyd-Steinberg baseline dithers (``_search_scale``): asked for 10^8 dots of a 48 x 32 picture,
# it grew its scaled image to 2.4 GB; fewer dots than asked come back where the bound stops it.
MAX_DITHER_PIXELS = 2**24


def _search_scale(image, count, dither):
    """``dither`` of ``image`` at the scale whose ink pixels are closest to ``count`` (eight tries), at most
    ``MAX_DITHER_PIXELS`` pixels."""
    columns, rows = image.size
    largest = np.sqrt(MAX_DITHER_PIXELS / (columns * rows))
    scale, best = min(1.0, largest), None
    for _ in range(8):
        size = (max(round(columns * scale), 1), max(round(rows * scale), 1))
        dithered, dots = dither(image.resize(size, Image.Resampling.LANCZOS))
        if best is None or abs(dots - count) < abs(best[1] - count):
            best = (dithered, dots)
        if dots in (count, 0) or (dots < count and scale >= largest):
            break
        scale = min(scale * np.sqrt(count / dots), largest)
    return best
