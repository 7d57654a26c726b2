import mpmath
import numpy as np
import pytest

from stipple.kernels import ball_kernel, distance_kernel


@pytest.mark.parametrize("radius", [0.0, 0.4, 1.0, np.sqrt(2), 3.7, 25.0, 181.3, 460.0, 919.2])
def test_ball_kernel_matches_hypergeometric_series(radius):
    exact = float(mpmath.pi**2 / 160 * mpmath.hyp2f3(1.5, 2.5, 2, 3, 3.5, -(mpmath.pi**2) * radius**2))
    # Evaluate inside a larger array: the cumulative integration must not depend on neighbours.
    radii = np.concatenate([np.linspace(0, 50, 97), [radius]])
    assert ball_kernel(radii)[-1] == pytest.approx(exact, rel=5e-14)


def test_ball_kernel_positive_with_cubic_decay():
    radii = np.linspace(1, 2000, 5000)
    values = ball_kernel(radii)
    assert np.all(values > 0)
    assert values[-1] * 16 * np.pi**2 * radii[-1] ** 3 == pytest.approx(1.0, rel=1e-3)


def test_distance_kernel_formula():
    k = distance_kernel(np.arange(6))
    assert k[0] == 0.0
    assert k[1] == pytest.approx(16 * np.pi / (5 * 3 * 1))
    n = 1e5
    assert distance_kernel(n) * n**3 == pytest.approx(2 * np.pi, rel=1e-4)
