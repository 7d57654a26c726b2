"""Quality measures of a point set against its density.

All formulas are documented in the README ("Evaluating point sets"); in short:

* ``E_N`` — the bandlimited quadrature error of the problem's own kernel at the points.
* ``E_N`` of i.i.d. samples — exactly ``lam^2 M sum_l mult_l k_l (E|psi_l(X)|^2 - |w_l/m|^2)`` for ``X ~ w/m``:
  ``E|psi_l|^2 = 1`` on the torus and ``sum_m mult |Y_nm|^2 = (2n+1)/(4 pi)`` on the sphere (addition theorem).
* Torus images: PSNR and SSIM between the density and the dots' density (one dot carries mass ``m/M``), both
  blurred by a periodic Gaussian of ``sigma`` pixels; the radially averaged power spectrum
  ``P(f) = |sum_i exp(-2 pi i n.x_i)|^2 / M`` over annuli ``|n| in [f, f+1)`` and its anisotropy
  ``10 log10(var / mean^2)`` in dB.
* Sphere: the minimum geodesic separation, and a spherical-cap discrepancy estimate
  ``max |#(points in cap)/M - w(cap)/m|`` over caps with 500 Fibonacci centres and 90 radii, the map's mass
  in each cap integrated over the cells the cap cuts (``stipple.sphere_caps``).
* Both (clumps): each dot's nearest-neighbour distance (pixels on the torus, geodesic radians on the sphere)
  over the spacing of a hexagonal packing of the local density, ``d_hex = sqrt(2 / (sqrt(3) rho))`` with
  ``rho = M w(x) / int w`` per pixel or steradian; min, 1st and 5th percentile and median over the dots
  outside the lightest cells that hold 1 % of the mass (:func:`light_threshold`).
"""

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from ..design import fibonacci_lattice
from ..halftone import hexagonal_spacing
from ..sampling import pixel_indices, pixel_positions
from ..sphere_caps import CapMasses
from ..sphere_density import density_at, local_density
from ..torus import periodic_blur

BLURS = (1.0, 2.0, 4.0)
# E|psi_l(X)|^2 as it enters sums whose weights depend on the degree only: 1 on the torus (|psi| = 1); on the
# sphere sum_m mult |Y_nm|^2 = (2n+1)/(4 pi) everywhere (addition theorem), i.e. 1/(4 pi) per stored order.
BASIS_SQUARE = {"torus": 1.0, "sphere": 1 / (4 * np.pi)}


def discrepancy_energy(problem, points):
    """The paper's bandlimited ``E_N`` of ``points`` for the problem's kernel and density."""
    problem.discrepancy.set_points(points)
    return problem.discrepancy.bandlimited_energy()


def untruncated_energy(problem, points):
    """The objective with its near field: the untruncated discrepancy (equal to ``E_N`` without a near field)."""
    problem.objective.set_points(points)
    return problem.objective.energy()


def expected_iid_energy(problem):
    """Exact expectation of ``E_N`` for ``M`` i.i.d. points drawn from the density."""
    discrepancy = problem.discrepancy
    mass = discrepancy.weight * problem.n_points
    normalised = discrepancy.target / mass
    variance = BASIS_SQUARE[problem.domain] - np.abs(normalised) ** 2
    return float(discrepancy.weight**2 * problem.n_points * np.sum(discrepancy.bandlimited_weights * variance))


def dot_density(points, shape, mass):
    """Dots binned on the pixel grid, each carrying ``mass / M`` (same units as the density)."""
    rows, columns = shape
    row, column = pixel_indices(points, shape)
    counts = np.bincount(row * columns + column, minlength=rows * columns).reshape(shape)
    return counts * (mass * rows * columns / len(points))


def psnr(reference, test):
    error = np.mean((reference - test) ** 2)
    peak = reference.max()
    return float("inf") if error == 0 else float(10 * np.log10(peak**2 / error))


def ssim(reference, test, data_range=1.0, sigma=1.5):
    """Structural similarity (Wang et al. 2004) with a Gaussian window, K1 = 0.01, K2 = 0.03."""
    c1, c2 = (0.01 * data_range) ** 2, (0.03 * data_range) ** 2
    mu_x, mu_y = (ndimage.gaussian_filter(image, sigma, mode="wrap") for image in (reference, test))
    var_x = ndimage.gaussian_filter(reference * reference, sigma, mode="wrap") - mu_x**2
    var_y = ndimage.gaussian_filter(test * test, sigma, mode="wrap") - mu_y**2
    cov = ndimage.gaussian_filter(reference * test, sigma, mode="wrap") - mu_x * mu_y
    index = ((2 * mu_x * mu_y + c1) * (2 * cov + c2)) / ((mu_x**2 + mu_y**2 + c1) * (var_x + var_y + c2))
    return float(index.mean())


def exact_blurs(weights, points, sigma, threads=1):
    """The density and the dots' density, both blurred by a periodic Gaussian of ``sigma`` pixels, exactly.

    Each dot carries mass ``mean(w) / M`` and is blurred as a point (not binned into a pixel first); the density is
    the pixel-constant image. Both are summed as Fourier series, ``G_n (lam c_n)`` and ``G_n w_n`` with the exact
    image coefficients and the Gaussian's ``G_n = exp(-2 pi² sigma² |n / size|²)``, over all frequencies up to
    where ``G`` falls below 1e-8, and evaluated at the pixel centres by NUFFTs. Returns two ``(H, W)`` arrays.
    """
    from ..nufft import make_nufft
    from ..torus_spectrum import image_coefficients
    from ..transforms import torus_modes

    rows, columns = weights.shape
    cycles = max(1.0, 0.97 / sigma)  # cycles per pixel beyond which exp(-2 pi² sigma² f²) < 1e-8
    bandwidths = (2 * int(np.ceil(cycles * columns)), 2 * int(np.ceil(cycles * rows)))
    nufft = make_nufft("ducc0", (bandwidths[0] + 1, bandwidths[1] + 1), 1e-10, threads)
    n1, n2 = torus_modes(nufft.shape)
    gaussian = np.exp(-2 * np.pi**2 * sigma**2 * ((n1 / columns) ** 2 + (n2 / rows) ** 2))
    nufft.set_points(np.mod(points, 1.0))
    dots = nufft.type1(np.ones((1, len(points)), dtype=np.complex128))[0] * (weights.mean() / len(points))
    return tuple(
        pixel_values(gaussian * coeffs, weights.shape).real
        for coeffs in (image_coefficients(weights, bandwidths), dots)
    )


def pixel_values(coeffs, shape):
    """``sum_n coeffs[n] exp(2 pi i n . p)`` at the centres ``p`` of the pixels of a ``shape = (H, W)`` grid, as an
    ``(H, W)`` array, for a centred mode array ``coeffs`` of shape ``(N1+1, N2+1)`` (``n1`` along x): the modes
    folded onto the grid, each alias ``n = k + m W`` with its sign ``(-1)^m`` at the half-pixel centres, then one
    inverse FFT. Exact; the type-2 NUFFT at the 12 million centres of a phone's photo took most of evaluate's 75 s."""
    rows, columns = shape
    folded = _fold(_fold(coeffs, columns, axis=0), rows, axis=1)
    folded = folded * np.exp(1j * np.pi * np.arange(columns) / columns)[:, None]
    folded *= np.exp(1j * np.pi * np.arange(rows) / rows)[None, :]
    return (np.fft.ifft2(folded) * (rows * columns)).T


def _fold(modes, length, axis):
    """The centred modes ``-N/2 .. N/2`` along ``axis`` summed onto ``0 .. length - 1`` by ``k = n mod length``,
    each with the sign ``(-1)^((n - k) / length)``."""
    modes = np.moveaxis(modes, axis, 0)
    count, lowest = modes.shape[0], -(modes.shape[0] // 2)
    blocks = -(-count // length)
    padded = np.zeros((blocks * length, *modes.shape[1:]), dtype=np.complex128)
    padded[:count] = modes
    summed = np.tensordot((-1.0) ** np.arange(blocks), padded.reshape(blocks, length, *modes.shape[1:]), axes=1)
    signs = (-1.0) ** np.floor_divide(lowest + np.arange(length), length)
    summed *= signs.reshape(-1, *[1] * (modes.ndim - 1))
    return np.moveaxis(np.roll(summed, lowest, axis=0), 0, axis)


def image_similarity(weights, points, blurs=BLURS):
    """PSNR and SSIM between the blurred density and the blurred dots, per blur width (pixels).

    ``psnr`` and ``ssim`` compare exact blurs (``exact_blurs``); ``psnr_binned`` is 0.1's measure, which bins the
    dots into pixels before blurring: its quantisation noise dominates at small blurs and it aliases regular
    patterns against the pixel grid.
    """
    binned = dot_density(points, weights.shape, weights.mean())
    results = []
    for sigma in blurs:
        reference, test = exact_blurs(weights, points, sigma)
        results.append(
            {
                "sigma": sigma,
                "psnr": psnr(reference, test),
                "ssim": ssim(reference, test),
                "psnr_binned": psnr(periodic_blur(weights, sigma), periodic_blur(binned, sigma)),
            }
        )
    return results


LIGHT_MASS_FRACTION = 0.01


def light_threshold(values, areas=1.0, fraction=LIGHT_MASS_FRACTION):
    """The density level at or below which dots are not judged by the neighbour measure.

    The largest cell value ``t >= 0`` such that the cells with ``w <= t`` carry at most ``fraction`` of the
    mass: dots in zero-density cells are always left out, and the lightest cells together hold about
    ``fraction`` of the dots. There the cell's value does not describe a dot's surroundings (a dot in a
    nearly white pixel sits at the spacing of its darker neighbours) and its ratio would fill the lowest
    percentiles.

    Parameters
    ----------
    values : numpy.ndarray
        Density on cells.
    areas : float or numpy.ndarray
        Cell areas (broadcast against ``values``).
    fraction : float
        Mass fraction of the lightest cells to leave out.

    Returns
    -------
    float
        Dots with ``w(x) > t`` are judged.
    """
    masses = np.ravel(values * np.broadcast_to(areas, np.shape(values)))
    values = np.ravel(values)
    order = np.argsort(values, kind="stable")
    cumulative = np.cumsum(masses[order])
    light = cumulative <= fraction * cumulative[-1]
    # A level is usable only if every cell with that value is within the light mass (ties stay together).
    usable = light & np.append(values[order][1:] != values[order][:-1], True)
    return float(max(values[order][usable].max(), 0.0)) if usable.any() else 0.0


def percentiles(ratios):
    """``min``, 1st and 5th percentile and median of the finite ``ratios`` (empty dict if none)."""
    ratios = ratios[np.isfinite(ratios)]
    if ratios.size == 0:
        return {}
    low, p01, p05, median = np.percentile(ratios, [0, 1, 5, 50])
    return {"min": float(low), "p01": float(p01), "p05": float(p05), "median": float(median)}


def local_spacing(density):
    """Spacing of a hexagonal packing with ``density`` points per unit area (``inf`` where it is 0, or so small
    that the division overflows: a map's tails of 1e-35)."""
    with np.errstate(divide="ignore", over="ignore"):
        return hexagonal_spacing(density, 1.0)


def torus_neighbours(points, weights):
    """Nearest-neighbour distance, local hexagonal spacing (both in pixels) and ``w`` at every point.

    Parameters
    ----------
    points : numpy.ndarray
        ``(M, 2)`` points in the unit square (the torus scaled to ``[0, W/L) x [0, H/L)``, ``L = max(W, H)``).
    weights : numpy.ndarray
        The density on the ``(H, W)`` pixel grid.

    Returns
    -------
    tuple of numpy.ndarray
        ``(distance, spacing, w)``; the local density is ``M w / sum(w)`` dots per pixel.
    """
    rows, columns = weights.shape
    pixels = pixel_positions(points, weights.shape)
    distances, _ = cKDTree(pixels, boxsize=np.array([columns, rows], dtype=float)).query(pixels, k=2)
    local = weights[pixel_indices(points, weights.shape)]
    return distances[:, 1], local_spacing(len(points) * local / weights.sum()), local


def torus_neighbour_ratios(points, weights):
    """Nearest-neighbour distance over the hexagonal spacing of the local density, for every point."""
    distance, spacing, _ = torus_neighbours(points, weights)
    return distance / spacing


def torus_clumps(points, weights):
    """Percentiles of the neighbour ratio over the judged dots (:func:`light_threshold`), and distances."""
    distance, spacing, local = torus_neighbours(points, weights)
    judged = local > light_threshold(weights)
    return {
        "neighbour_distance_over_hexagonal": percentiles(distance[judged] / spacing[judged]),
        "neighbour_points_judged": int(judged.sum()),
        "median_neighbour_distance_pixels": float(np.median(distance)),
    }


def sphere_clumps(points, density):
    """Geodesic nearest-neighbour distance over the hexagonal spacing of ``rho = M w / int w`` (per sr).

    Dots are judged as on the torus (:func:`light_threshold` on the density's cells); the median
    nearest-neighbour distance (radians) is over all dots.
    """
    chords, _ = cKDTree(points).query(points, k=2)
    distance = 2 * np.arcsin(np.minimum(chords[:, 1] / 2, 1.0))
    local = density_at(density, points)
    spacing = local_spacing(local_density(density, points))
    cells = density if hasattr(density, "values") else density.cell_map()
    judged = local > light_threshold(cells.values, cells.cell_areas)
    return {
        "neighbour_distance_over_hexagonal": percentiles(distance[judged] / spacing[judged]),
        "neighbour_points_judged": int(judged.sum()),
        "median_neighbour_distance_radians": float(np.median(distance)),
    }


def power_spectrum(problem, points, max_frequency=None):
    """Radially averaged periodogram and anisotropy (dB) over integer annuli of the mode grid."""
    fourier = problem.discrepancy.fourier
    fourier.set_points(points)
    coeffs = fourier.analysis()
    n1, n2 = fourier.modes
    radius = np.hypot(n1, n2)
    limit = max_frequency or int(min(n1.max(), n2.max()))
    periodogram = np.abs(coeffs) ** 2 / len(points)
    frequencies, means, anisotropy = [], [], []
    for f in range(1, limit):
        ring = periodogram[(radius >= f) & (radius < f + 1)]
        if ring.size == 0:
            continue
        frequencies.append(f)
        means.append(float(ring.mean()))
        anisotropy.append(float(10 * np.log10(ring.var() / ring.mean() ** 2)) if ring.mean() > 0 else None)
    return {"frequency": frequencies, "power": means, "anisotropy_db": anisotropy}


def minimum_separation(points):
    """Smallest geodesic distance (radians) between two points."""
    distances, _ = cKDTree(points).query(points, k=2)
    chord = distances[:, 1].min()
    return float(2 * np.arcsin(min(chord / 2, 1.0)))


def cap_discrepancy(points, cells, centres=500, radii=90):
    """``max |fraction of points in cap - fraction of mass in cap|`` over a grid of caps.

    The map's mass in each cap is integrated over the cells the cap's edge cuts
    (``stipple.sphere_caps.CapMasses``), not put at the cells' centres.
    """
    directions = fibonacci_lattice(centres)
    heights = np.cos(np.linspace(0, np.pi, radii + 2)[1:-1])
    mass_above = CapMasses(cells)
    worst = 0.0
    for direction in directions:
        point_heights = np.sort(points @ direction)
        # Cap {x : x . direction >= h}: everything above height h.
        points_above = 1 - np.searchsorted(point_heights, heights, side="left") / len(points)
        worst = max(worst, float(np.abs(points_above - mass_above(direction, heights)).max()))
    return worst


def evaluate_torus(problem, points, weights):
    """All torus measures as a dict (see the module docstring)."""
    energy = discrepancy_energy(problem, points)
    expected = expected_iid_energy(problem)
    report = {
        "domain": "torus",
        "points": len(points),
        "bandwidth": problem.bandwidth,
        "energy": energy,
        "expected_iid_energy": expected,
        "energy_ratio_to_iid": energy / expected,
        "untruncated_energy": untruncated_energy(problem, points),
        "similarity": image_similarity(weights, points),
        **torus_clumps(points, weights),
    }
    report["spectrum"] = power_spectrum(problem, points)
    report["flat_input"] = bool(np.ptp(weights) <= 1e-12 * max(weights.max(), 1e-300))
    return report


def evaluate_sphere(problem, points, density):
    """All sphere measures as a dict (see the module docstring)."""
    from ..design import largest_error

    expected = expected_iid_energy(problem)
    cells = density.cell_map()
    energy = discrepancy_energy(problem, points)
    coefficient_error = largest_error(problem.discrepancy)
    return {
        "domain": "sphere",
        "points": len(points),
        "bandwidth": problem.bandwidth,
        "energy": energy,
        "expected_iid_energy": expected,
        "energy_ratio_to_iid": energy / expected,
        "untruncated_energy": untruncated_energy(problem, points),
        "max_coefficient_error": coefficient_error,
        "minimum_separation_degrees": float(np.degrees(minimum_separation(points))),
        "cap_discrepancy": cap_discrepancy(points, cells),
        **sphere_clumps(points, density),
    }


# One-line drawings: the drawn line's ink against the image.


def line_ink(pixels, shape, pen_width=1.0, closed=True):
    """Ink (0 white .. 1 black) of a polyline through ``pixels`` drawn ``pen_width`` pixels wide, per pixel."""
    from ..io.png import render_line

    rows, columns = shape
    image = render_line(pixels, (columns, rows), columns, pen_width, closed=closed)
    return 1 - np.asarray(image, dtype=np.float64) / 255


def fitted_similarity(weights, ink, blurs=(2.0, 4.0)):
    """PSNR and SSIM of blurred ``ink`` scaled by least squares onto the blurred density, per blur (pixels).

    The scale ``a = <B w, B ink> / <B ink, B ink>`` makes the comparison blind to the tone scale of the pen.
    """
    results = []
    for sigma in blurs:
        reference, drawn = periodic_blur(weights, sigma), periodic_blur(ink, sigma)
        scale = float(np.sum(reference * drawn) / max(np.sum(drawn * drawn), 1e-300))
        fitted = scale * drawn
        results.append({"sigma": sigma, "psnr": psnr(reference, fitted), "ssim": ssim(reference, fitted), "ink": scale})
    return results


def curve_energy(problem, points):
    """The line objective without its speed penalty: the discrepancy with the curve's near field."""
    discrepancy, near = problem.objective.terms[:2]
    for term in (discrepancy, near):
        term.set_points(points)
    return discrepancy.energy() + near.energy()


def evaluate_line(problem, points, weights, pen_width=1.0):
    """``E_N`` of the curve's vertex measure, the segment statistics, and the drawn line against the image.

    ``points`` are in the image's unit coordinates; ``problem`` is a ``line_problem`` (its torus adds a margin).
    """
    rows, columns = weights.shape
    pixels = points * np.array([columns, rows])
    segments = np.linalg.norm(np.roll(pixels, -1, axis=0) - pixels, axis=1)
    points = problem.manifold.inward(points)
    energy = discrepancy_energy(problem, points)
    expected = expected_iid_energy(problem)
    return {
        "domain": "line",
        "points": len(points),
        "bandwidth": problem.bandwidth,
        "energy": energy,
        "expected_iid_energy": expected,
        "energy_ratio_to_iid": energy / expected,
        "untruncated_energy": curve_energy(problem, points),
        "length_pixels": float(segments.sum()),
        "max_over_mean_segment": float(segments.max() / segments.mean()),
        "min_over_mean_segment": float(segments.min() / segments.mean()),
        "similarity": fitted_similarity(weights, line_ink(pixels, weights.shape, pen_width)),
    }
