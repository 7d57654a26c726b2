import numpy as np
import pytest
from conftest import backend_params

import stipple.nufft
from stipple.nufft import BACKENDS, Ducc0Nufft, FinufftNufft, ResidueSplitNufft, make_nufft
from stipple.precision import SINGLE_PRECISION_EPSILON, precision
from stipple.transforms import TorusFourier, torus_modes


def direct_matrix(points, shape):
    """exp(-2 pi i n . p_i) for every point and mode, shape (M, N1+1, N2+1)."""
    n1, n2 = torus_modes(shape)
    return np.exp(-2j * np.pi * (n1[None] * points[:, 0, None, None] + n2[None] * points[:, 1, None, None]))


@pytest.mark.parametrize("backend", backend_params(BACKENDS))
def test_nufft_against_direct_sums(backend, rng):
    shape = (11, 7)
    points = rng.random((60, 2))
    nufft = make_nufft(backend, shape, 1e-12, 1)
    nufft.set_points(points)
    matrix = direct_matrix(points, shape)
    values = rng.standard_normal((2, 60)) + 1j * rng.standard_normal((2, 60))
    coeffs = rng.standard_normal((2,) + shape) + 1j * rng.standard_normal((2,) + shape)
    np.testing.assert_allclose(nufft.type1(values), np.einsum("bm,mxy->bxy", values, matrix), atol=1e-9)
    np.testing.assert_allclose(nufft.type2(coeffs), np.einsum("bxy,mxy->bm", coeffs, matrix.conj()), atol=1e-9)


@pytest.mark.parametrize("backend_class", [Ducc0Nufft, FinufftNufft])
@pytest.mark.parametrize("threads", [2, 3])
@pytest.mark.parametrize("shape", [(11, 7), (13, 9), (21, 5)])
def test_residue_split_type1_against_direct_sums(backend_class, threads, shape, rng):
    """Every residue class of n1 (odd and even half-widths, offsets that need a shift) lands on its own rows."""
    points = rng.random((60, 2)) * 3 - 1  # outside [0, 1): folding must still be periodic
    nufft = ResidueSplitNufft(backend_class, shape, 1e-12, threads)
    nufft.set_points(points)
    matrix = direct_matrix(points, shape)
    values = rng.standard_normal((2, 60)) + 1j * rng.standard_normal((2, 60))
    coeffs = rng.standard_normal((1,) + shape) + 1j * rng.standard_normal((1,) + shape)
    np.testing.assert_allclose(nufft.type1(values), np.einsum("bm,mxy->bxy", values, matrix), atol=1e-9)
    np.testing.assert_allclose(nufft.type2(coeffs), np.einsum("bxy,mxy->bm", coeffs, matrix.conj()), atol=1e-9)
    assert nufft.counts["type1"] == 2 and nufft.counts["type2"] == 1


def test_threads_take_the_split_path_only_where_it_pays():
    assert isinstance(make_nufft("ducc0", (129, 129), 1e-9, 2), ResidueSplitNufft)
    assert isinstance(make_nufft("ducc0", (33, 33), 1e-9, 2), Ducc0Nufft)
    assert make_nufft("ducc0", (33, 33), 1e-9, 2).threads == 1


@pytest.mark.parametrize("backend", backend_params(BACKENDS[1:]))
def test_backends_agree_on_a_large_problem(backend, rng):
    shape = (201, 201)
    points = rng.random((5000, 2))
    values = rng.standard_normal((1, 5000)) + 0j
    results = []
    for name in ("ducc0", backend):
        nufft = make_nufft(name, shape, 1e-9, 2)
        nufft.set_points(points)
        results.append(nufft.type1(values)[0])
    scale = np.abs(results[0]).max()
    assert np.abs(results[0] - results[1]).max() < 1e-8 * scale


def test_packed_gradient_transforms_match_direct_formulas(rng):
    shape = (9, 13)
    points = rng.random((40, 2))
    fourier = TorusFourier(make_nufft("ducc0", shape, 1e-13, 1))
    fourier.set_points(points)
    matrix = direct_matrix(points, shape)
    n1, n2 = torus_modes(shape)
    # A Hermitian coefficient array, as every residual of real data is.
    coeffs = fourier.analysis() * (1 + n1**2 + n2**2) ** -1.0
    expected = np.stack(
        [np.real(np.einsum("xy,mxy->m", 2j * np.pi * n * coeffs, matrix.conj())) for n in (n1, n2)], axis=1
    )
    np.testing.assert_allclose(fourier.gradient_synthesis([coeffs])[0], expected, atol=1e-10)
    vectors = rng.standard_normal((40, 2))
    expected = np.einsum(
        "mxy,mxy->xy",
        -2j * np.pi * (n1[None] * vectors[:, 0, None, None] + n2[None] * vectors[:, 1, None, None]),
        matrix,
    )
    np.testing.assert_allclose(fourier.gradient_analysis([vectors])[0], expected, atol=1e-10)
    second = np.einsum("xy,mxy->m", -4 * np.pi**2 * n1 * n2 * coeffs, matrix.conj()).real
    np.testing.assert_allclose(fourier.hessian_synthesis(coeffs)[:, 0, 1], second, atol=1e-9)


@pytest.mark.parametrize("backend", backend_params(BACKENDS))
@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("shape", [(9, 7), (11, 5), (13, 9)])
def test_analysis_mirrors_its_half_grid_into_the_direct_sums(monkeypatch, backend, threads, shape, rng):
    """``analysis`` transforms the rows n1 >= 0 (N1/2 even and odd: the half grid gets an extra row or not) and
    mirrors them; with 2 threads both CPU grids take the residue split."""
    monkeypatch.setattr(stipple.nufft, "MIN_ROWS_PER_THREAD", 1)
    points = rng.random((50, 2)) * 3 - 1
    fourier = TorusFourier(make_nufft(backend, shape, 1e-12, threads))
    assert fourier.half_nufft.shape[0] % 2 == 1 and fourier.half_nufft.shape[0] >= shape[0] // 2 + 1
    assert isinstance(fourier.half_nufft, ResidueSplitNufft) == (threads > 1 and backend != "cufinufft")
    fourier.set_points(points)
    np.testing.assert_allclose(fourier.analysis(), direct_matrix(points, shape).sum(0), atol=1e-10)
    assert fourier.counts["type1"] == 1


def test_residue_split_type2_uses_the_points_given_to_set_points(rng):
    """The type-2 plan is made at the first type-2 transform: from the points as they were at ``set_points``."""
    shape = (13, 9)
    points = rng.random((40, 2))
    expected = np.einsum("bxy,mxy->bm", np.ones((1,) + shape), direct_matrix(points, shape).conj())
    nufft = ResidueSplitNufft(Ducc0Nufft, shape, 1e-12, 2)
    nufft.set_points(points)
    points[:] = 0.5  # the caller reuses its array
    np.testing.assert_allclose(nufft.type2(np.ones((1,) + shape, dtype=np.complex128)), expected, atol=1e-9)


@pytest.mark.parametrize("backend", backend_params(BACKENDS))
@pytest.mark.parametrize("threads", [1, 2])
def test_single_precision_transforms_against_direct_sums(monkeypatch, backend, threads, rng):
    """At an epsilon of 1e-4 the transforms run in single precision and still match direct sums to that accuracy
    (relative to the sums of magnitudes, the libraries' bound), also for points outside [0, 1) and on the CPU's
    residue split (2 threads); results come back in double precision."""
    monkeypatch.setattr(stipple.nufft, "MIN_ROWS_PER_THREAD", 1)
    shape = (21, 13)
    points = rng.random((200, 2)) * 3 - 1
    nufft = make_nufft(backend, shape, 1e-4, threads)
    assert isinstance(nufft, ResidueSplitNufft) == (threads > 1 and backend != "cufinufft")
    nufft.set_points(points)
    matrix = direct_matrix(points, shape)
    values = rng.standard_normal((2, 200)) + 1j * rng.standard_normal((2, 200))
    coeffs = rng.standard_normal((2,) + shape) + 1j * rng.standard_normal((2,) + shape)
    forward, backward = nufft.type1(values), nufft.type2(coeffs)
    assert forward.dtype == backward.dtype == np.complex128
    exact_forward = np.einsum("bm,mxy->bxy", values, matrix)
    exact_backward = np.einsum("bxy,mxy->bm", coeffs, matrix.conj())
    assert np.abs(forward - exact_forward).max() < 1e-4 * np.abs(values).sum(axis=1).max()
    assert np.abs(backward - exact_backward).max() < 1e-4 * np.abs(coeffs).sum(axis=(1, 2)).max()
    # Single precision is not double precision: the same transforms at 1e-12 are much closer.
    assert np.abs(forward - exact_forward).max() > 1e3 * 1e-12 * np.abs(values).sum(axis=1).max()


def test_precision_follows_epsilon():
    assert precision(SINGLE_PRECISION_EPSILON) == (np.float32, np.complex64)
    assert precision(1e-7) == (np.float64, np.complex128)


def test_single_precision_gradient_synthesis_rounds_its_products_once_in_place(rng):
    """The gradient's coefficients times ``2 pi i (n1 + i n2)`` are made in double precision and stored straight
    in the transform's single precision: the bits of converting the double-precision products, without a
    grid-sized double-precision array or a converted copy (tracemalloc sees numpy's arrays)."""
    import tracemalloc

    shape = (201, 301)
    fourier = TorusFourier(make_nufft("ducc0", shape, 1e-4, 1), analysis_epsilon=1e-7)
    fourier.set_points(rng.random((500, 2)))
    coeffs = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    converted = (fourier._synthesis_factor * coeffs).astype(np.complex64)
    expected = fourier.nufft.type2(converted[None])[0]
    tracemalloc.start()
    try:
        (field,) = fourier.gradient_synthesis([coeffs])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert np.array_equal(field, np.stack([expected.real, expected.imag], axis=1))
    assert peak < 1.5 * np.prod(shape) * np.dtype(np.complex64).itemsize
