"""Numerical spherical designs: M points whose equal-weight rule integrates every harmonic of degree <= t.

A design of strength t is a zero of ``E = sum_{1 <= n <= t} k_n sum_m |F_nm|^2`` with ``F_nm`` the quadrature
error of ``Y_nm`` (Gräf & Potts 2011). With ``k_n = (1 + n(n+1))^-1`` (``sobolev:1``) the Gauss-Newton Hessian's
eigenvalues ``~ k_n n(n+1) M / 4 pi`` are flat in n, so CG needs no further preconditioning; what decides the
iteration count is how many points there are per harmonic. Measured from a uniform start (README, "Spherical
designs"): at degree 100, ``M = c (t+1)^2`` points took 2589 iterations for c = 0.51, 535 for 0.55, 222 for 0.6,
90 for 0.7 and 51 for c = 1; at degrees 200 and 400 with c = 1 also 51 or 52.

The start decides how well separated the design is. From i.i.d. points, the many free directions of ``c >= 0.65``
leave near-coincident pairs (c = 1: smallest nearest-neighbour distance 0.015 of the hexagonal spacing); from the
spherical Fibonacci lattice jittered by 0.1 spacings it is 0.55 (69 iterations). Below 0.65 the equations
separate the points themselves (c = 0.55: 0.64) and lattice starts are slow (6979 iterations), so i.i.d. points
are the start there.
"""

import numpy as np

from .errors import StippleError
from .halftone import MAX_BANDWIDTH, MAX_POINTS, check_integer, run
from .sphere import sphere_problem, unit_vectors

DESIGN_KERNEL = "sobolev:1"
DESIGN_EPSILON = 1e-12
# Default points per harmonic: 10 % above the (t+1)^2 / 2 at which the system of equations becomes square.
POINTS_PER_HARMONIC = 0.55
TARGET_ERROR = 1e-10
# CG's relative-gradient stop, far below what the error target needs: a floor for targets the transforms'
# accuracy cannot reach.
GRADIENT_FLOOR = 1e-14
# A run whose energy stops falling has stalled (``stipple.sphere.STALLED``, the settle of every problem without a
# map): t = 3 with 5 points sat at a relative gradient of 1.4e-14, above the floor, for all 20000 iterations.
# Start on the jittered Fibonacci lattice from this many points per harmonic on; i.i.d. uniform below.
LATTICE_FROM = 0.65
LATTICE_JITTER = 0.1
STARTS = ("auto", "lattice", "uniform")


# Hardin & Sloane (1996): for these strengths designs are known to exist for every number of points from this
# one on, while some smaller sizes have none (no 2-design with 5 points, 3-design with 9, 6-design with 27,
# which are exactly where ceil(0.55 (t+1)^2) stalled at a local minimum among t = 1..60).
EVERY_SIZE_FROM = {2: 6, 3: 10, 4: 16, 5: 22, 6: 28, 7: 36, 8: 44, 9: 54, 10: 64, 11: 74, 12: 86}


def design_points(strength):
    """Default number of points for strength t: ``ceil(0.55 (t+1)^2)``, and for t <= 12 at least the size from
    which Hardin & Sloane found designs of every size."""
    strength = check_strength(strength)
    return max(int(np.ceil(POINTS_PER_HARMONIC * (strength + 1) ** 2)), EVERY_SIZE_FROM.get(strength, 0))


def check_strength(strength):
    return check_integer("strength (degree t)", strength, 1, MAX_BANDWIDTH)


def largest_error(discrepancy):
    """``max |F_nm|`` over ``1 <= n <= t``: the largest quadrature error of an orthonormal harmonic."""
    return float(np.abs(discrepancy.residual[1:]).max())


# Largest errors below this are rounding: a run that stalls there is a design as far as doubles go (t = 20: 6.6e-14).
ROUNDING_FLOOR = 1e-12


class ErrorTarget:
    """A CG callback that stops the run once the largest error is at most ``error``."""

    def __init__(self, discrepancy, error):
        self.discrepancy = discrepancy
        self.error = error
        self.largest = np.inf

    def __call__(self, state):
        if self.discrepancy.residual is None:  # resumed: no transform at the saved points yet
            self.discrepancy.set_points(state.points)
        self.largest = largest_error(self.discrepancy)
        return self.reached

    @property
    def reached(self):
        return self.largest <= self.error


def fibonacci_lattice(n_points, rng=None, jitter=0.0):
    """The spherical Fibonacci lattice ``z_i = 1 - (2i+1)/M``, ``phi_i = 2 pi i / golden ratio``, each point moved
    by ``jitter`` hexagonal spacings times a standard normal vector (then projected back)."""
    index = np.arange(n_points)
    points = unit_vectors(1 - (2 * index + 1) / n_points, 2 * np.pi * index * 2 / (1 + np.sqrt(5)))
    if jitter:
        points += jitter * np.sqrt(4 * np.pi / n_points) * rng.standard_normal(points.shape)
        points /= np.linalg.norm(points, axis=1, keepdims=True)
    return points


def start_points(strength, n_points, init="auto", seed=0):
    """The start for ``init``: "lattice" (jittered Fibonacci), "uniform" (i.i.d.), "auto" (lattice from
    ``LATTICE_FROM (t+1)^2`` points on), or an array passed through."""
    if not isinstance(init, str):
        return init
    if init not in STARTS:
        raise StippleError(f"init must be one of {', '.join(STARTS)} or an array, not {init!r}")
    if init == "auto":
        init = "lattice" if n_points >= LATTICE_FROM * (strength + 1) ** 2 else "uniform"
    if init == "uniform":
        return init
    return fibonacci_lattice(n_points, np.random.default_rng(seed), LATTICE_JITTER)


def design_problem(strength, n_points=None, *, threads=None, epsilon=DESIGN_EPSILON):
    """The ``Problem`` of a design of strength t with ``n_points`` points (default ``design_points(t)``)."""
    strength = check_strength(strength)
    if n_points is None and design_points(strength) > MAX_POINTS:  # the count no one gave would be blamed
        raise StippleError(
            f"strength {strength} asks for {design_points(strength)} points by default, more than {MAX_POINTS}: "
            "give a smaller strength"
        )
    n_points = design_points(strength) if n_points is None else n_points
    fewest = -(-((strength + 1) ** 2) // 4)  # (t+1)^2/4 rounded up: t = 2 needs 3 points, not 2
    if isinstance(n_points, (int, np.integer)) and 0 < n_points < fewest:
        raise StippleError(
            f"number of points must be at least (t+1)^2/4, rounded up: {fewest} for strength {strength} "
            f"(designs need about (t+1)^2/2 points), not {n_points}"
        )
    return sphere_problem(
        None, n_points, strength, kernel=DESIGN_KERNEL, threads=threads, epsilon=epsilon, near_field=False
    )


def spherical_design(
    strength,
    n_points=None,
    *,
    error=TARGET_ERROR,
    threads=None,
    epsilon=DESIGN_EPSILON,
    init="auto",
    seed=0,
    callback=None,
    **options,
):
    """Compute a numerical spherical design of strength ``strength``.

    Parameters
    ----------
    strength : int
        Degree t: every spherical harmonic of degree ``1 <= n <= t`` is to be integrated to within ``error``.
    n_points : int, optional
        Number of points M (default ``ceil(0.55 (t+1)^2)``; at least ``(t+1)^2 / 4``). More points converge in
        fewer iterations: ``(t+1)^2`` takes about 50 at any degree measured.
    error : float
        Stop once ``max_nm |(4 pi / M) sum_i Y_nm(x_i)|`` is at most this (default 1e-10).
    threads, epsilon :
        Transform threads (default: all CPUs) and accuracy (default 1e-12).
    init : {"auto", "lattice", "uniform"} or array
        Start (see ``start_points``): the Fibonacci lattice jittered by 0.1 spacings where ``M >= 0.65 (t+1)^2``
        (so that the many free directions do not keep near-coincident points), i.i.d. uniform below; or an
        (M, 3) array.
    seed : int
        Seed of the start's randomness.
    callback : callable, optional
        ``callback(state)`` after every iteration; returning True stops the run.
    **options
        ``iterations`` (default 20000), ``time_limit``, ``checkpoint``, ... as for
        ``stipple.halftone.run``.

    Returns
    -------
    HalftoneResult
        ``status`` is "converged" when the error target was reached; ``message`` states the largest error.
    """
    if not isinstance(error, (int, float)) or not 0 < error < 1:
        raise StippleError(f"error must be a number in (0, 1), not {error!r}")
    if "tol" in options:
        raise StippleError("a design stops by its error (error=), not by tol")
    problem = design_problem(strength, n_points, threads=threads, epsilon=epsilon)
    target = ErrorTarget(problem.discrepancy, error)

    def chained(state):
        stop = callback is not None and bool(callback(state))  # shown every iteration, the last one too
        return target(state) or stop

    options.setdefault("iterations", 20000)
    init = start_points(strength, problem.n_points, init, seed)
    result = run(problem, init=init, seed=seed, tol=GRADIENT_FLOOR, callback=chained, **options)
    return design_outcome(result, target, accurate_check(strength, problem.n_points, threads, epsilon))


def accurate_check(strength, n_points, threads, epsilon):
    """The discrepancy that measures a run's final points at ``DESIGN_EPSILON`` where the run's transforms were
    looser (None otherwise): t = 8 at ``epsilon`` 1e-6 stopped at a reported 8.8e-11 whose largest error
    measured at 1e-12 is 3.6e-7."""
    if epsilon <= DESIGN_EPSILON:
        return None
    return design_problem(strength, n_points, threads=threads, epsilon=DESIGN_EPSILON).discrepancy


def design_outcome(result, target, accurate=None):
    """``result`` with status and message telling whether the error target was reached (measured again by
    ``accurate``, ``accurate_check``'s discrepancy, if given)."""
    if accurate is not None:
        accurate.set_points(result.points)
        reached = target.reached
        target.largest = largest_error(accurate)
        if reached and not target.reached:
            result.status = "stalled"
            result.message = (
                f"the transforms' accuracy (epsilon) is too loose for the target: largest error "
                f"{target.largest:.3g} > target {target.error:g}, measured at {DESIGN_EPSILON:g} after "
                f"{result.iterations} iterations"
            )
            return result
    if target.reached:
        result.status = "converged"
        result.message = f"largest error {target.largest:.3g} <= {target.error:g} after {result.iterations} iterations"
        return result
    stuck = result.status in ("converged", "settled")  # the gradient vanished, or the energy stopped falling
    if stuck and target.largest < ROUNDING_FLOOR:  # as close as double precision gets
        result.status = "stalled"
        result.message = (
            f"stopped at the floating-point floor after {result.iterations} iterations (a design to rounding; "
            f"a tighter --error than about {ROUNDING_FLOOR:g} cannot be reached in double precision)"
        )
    elif stuck:  # away from a design: a local minimum
        result.status = "stalled"
        result.message = (
            f"stalled at a local minimum after {result.iterations} iterations (not a design; for small t some "
            "numbers of points have none: try more points or another --seed)"
        )
    result.message += f"; largest error {target.largest:.3g} > target {target.error:g}"
    return result
