import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


def taylor_slope(function, steps):
    """Least-squares slope of log|remainder| against log(step)."""
    remainders = np.array([abs(function(t)) for t in steps])
    return np.polyfit(np.log(steps), np.log(remainders), 1)[0]


def energy_at(objective, points):
    objective.set_points(points)
    return objective.energy()


def assert_derivatives_alike(exact, single, points, other):
    """Two problems that differ only in their derivatives' accuracy: the same energy to 1e-12 (the residual keeps
    its ``epsilon``), the gradient and the Hessian form on ``[gradient, other]`` within 1e-4 and not the same."""
    results = []
    for problem in (exact, single):
        problem.objective.set_points(points)
        gradient = np.array(problem.objective.gradient())
        results.append((problem.objective.energy(), gradient, problem.objective.hessian_gram([gradient, other])))
    (energy, gradient, gram), (energy_single, gradient_single, gram_single) = results
    assert energy_single == pytest.approx(energy, rel=1e-12)
    assert 0 < np.linalg.norm(gradient_single - gradient) < 1e-4 * np.linalg.norm(gradient)
    np.testing.assert_allclose(gram_single, gram, rtol=1e-4)


def gradient_taylor_slope(objective, points, direction, steps):
    """Slope of ``|E(p + t d) - E(p) - t <grad E, d>|`` in t (2 for a correct gradient)."""
    objective.set_points(points)
    energy, gradient = objective.energy(), objective.gradient()
    linear = np.sum(gradient * direction)
    return taylor_slope(lambda t: energy_at(objective, points + t * direction) - energy - t * linear, steps)


def hessian_taylor_slope(objective, points, direction, steps):
    """Slope of the remainder after the quadratic term (3 for a correct Hessian), and ``H d``."""
    objective.set_points(points)
    energy, gradient = objective.energy(), objective.gradient()
    (hess_direction,) = objective.hessian_vectors([direction])
    linear, quadratic = np.sum(gradient * direction), 0.5 * np.sum(direction * hess_direction)

    def remainder(t):
        objective_energy = energy_at(objective, points + t * direction)
        return objective_energy - energy - t * linear - t**2 * quadratic

    slope = taylor_slope(remainder, steps)
    objective.set_points(points)
    return slope, hess_direction


def _gpu_available():
    from stipple.errors import StippleError
    from stipple.gpu import require_gpu

    try:
        require_gpu()
    except StippleError:
        return False
    return True


# The GPU backend's tests run where the ``gpu`` extra and a device are there (a lent GPU machine), else skip.
needs_gpu = pytest.mark.skipif(not _gpu_available(), reason="needs cufinufft, CuPy and an NVIDIA GPU")


def backend_params(backends):
    """``backends`` for ``pytest.mark.parametrize``, the GPU's marked ``needs_gpu``."""
    return [pytest.param(name, marks=needs_gpu) if name == "cufinufft" else name for name in backends]
