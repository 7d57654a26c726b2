"""The shared driver: a problem (manifold + objective + sampler) and a CG run on it."""

import os
from dataclasses import dataclass

import numpy as np

from .errors import StippleError
from .optimize import minimize

MAX_POINTS = 20_000_000
MAX_BANDWIDTH = 8192
INITS = ("density", "uniform")


@dataclass
class Problem:
    """A halftoning problem ready to optimise.

    ``sample(rng, count)`` draws i.i.d. points from the density; ``settings`` are the values that
    define the problem (compared when a checkpoint is resumed).
    """

    domain: str
    manifold: object
    objective: object
    n_points: int
    bandwidth: int
    sample: object
    settings: dict


@dataclass
class HalftoneResult:
    """Points and how the run went (see ``stipple.optimize.OptimizeResult`` for the fields)."""

    points: np.ndarray
    status: str
    message: str
    iterations: int
    energy: float
    relative_gradient_norm: float
    energies: np.ndarray
    gradient_norms: np.ndarray
    seconds: float
    bandwidth: int
    state: object

    @property
    def success(self):
        return self.status in ("converged", "max_iterations", "time_limit")


def default_threads():
    """The number of CPUs this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def check_count(n_points):
    if isinstance(n_points, bool) or not isinstance(n_points, (int, np.integer)) or not 1 <= n_points <= MAX_POINTS:
        raise StippleError(f"number of points must be an integer in [1, {MAX_POINTS}], not {n_points!r}")
    return int(n_points)


def check_bandwidth(bandwidth):
    valid = isinstance(bandwidth, (int, np.integer)) and not isinstance(bandwidth, bool)
    if not valid or not 2 <= bandwidth <= MAX_BANDWIDTH or bandwidth % 2:
        raise StippleError(f"bandwidth must be an even integer in [2, {MAX_BANDWIDTH}], not {bandwidth!r}")
    return int(bandwidth)


def check_positive(name, value, allow_none=False):
    if value is None and allow_none:
        return None
    if not isinstance(value, (int, float, np.number)) or not np.isfinite(value) or value <= 0:
        raise StippleError(f"{name} must be a positive number, not {value!r}")
    return value


def initial_points(problem, init, rng):
    """Starting points: i.i.d. from the density, i.i.d. uniform, or given (checked for shape)."""
    if isinstance(init, str):
        if init not in INITS:
            raise StippleError(f"init must be one of {', '.join(INITS)} or an array, not {init!r}")
        if init == "density":
            return problem.sample(rng, problem.n_points)
        return problem.manifold.random(rng, problem.n_points)
    points = np.asarray(init, dtype=np.float64)
    expected = (problem.n_points, problem.manifold.dimension)
    if points.shape != expected:
        raise StippleError(f"initial points must have shape {expected}, not {points.shape}")
    if not np.all(np.isfinite(points)):
        raise StippleError("initial points contain NaN or infinite values")
    return points


def run(
    problem,
    *,
    init="density",
    seed=0,
    tol=1e-4,
    iterations=2000,
    time_limit=None,
    restart_every=None,
    callback=None,
    state=None,
):
    """Optimise ``problem`` from ``init`` (or continue from ``state``) and collect the result."""
    check_positive("tol", tol)
    check_positive("time_limit", time_limit, allow_none=True)
    if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) or iterations < 0:
        raise StippleError(f"iterations must be a non-negative integer, not {iterations!r}")
    points = None
    if state is None:
        points = initial_points(problem, init, np.random.default_rng(seed))
    outcome = minimize(
        problem.objective,
        problem.manifold,
        points,
        state=state,
        tol=tol,
        max_iterations=iterations,
        time_limit=time_limit,
        restart_every=restart_every,
        callback=callback,
    )
    return HalftoneResult(
        points=outcome.points,
        status=outcome.status,
        message=outcome.message,
        iterations=outcome.iterations,
        energy=outcome.energy,
        relative_gradient_norm=outcome.relative_gradient_norm,
        energies=outcome.energies,
        gradient_norms=outcome.gradient_norms,
        seconds=outcome.seconds,
        bandwidth=problem.bandwidth,
        state=outcome.state,
    )
