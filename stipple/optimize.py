"""Nonlinear conjugate gradients with a Newton step (Gräf, Potts, Steidl §4.2).

Euclidean on the torus and Riemannian on the sphere: the manifold supplies inner products,
retraction (exponential map) and transport; the objective supplies energy, differential and
Hessian-vector products at its current points.

Two rules for ``beta``: the paper's, Daniel's ``<h', H' d~> / <d~, H' d~>``, needs the Hessian's form on two
fields at the new points (two Jacobian fields, one transform each on the torus); Hestenes-Stiefel's
``<h', y> / <d~, y>`` with ``y = h' - h~`` takes the Hessian's action along ``d~`` from the change of the
gradient (equal to Daniel's on a quadratic) and needs the form on the new direction only.
"""

import time
from dataclasses import dataclass, field, replace

import numpy as np

# ``settle`` compares the energy with the one this many iterations before.
SETTLE_WINDOW = 20
BETAS = ("hestenes-stiefel", "daniel")


@dataclass
class CGState:
    """Everything the iteration needs to continue; saved by checkpoints as it is.

    ``gradient_curvature`` and ``direction_curvature`` are ``<h, H h>`` and ``<d, H d>`` at ``points``
    (``gradient_curvature`` is 0 where the beta rule did not need it; it is read only when ``<d, H d>`` is not
    positive, which Hestenes-Stiefel's steps never leave).
    """

    points: np.ndarray
    gradient: np.ndarray
    direction: np.ndarray
    gradient_curvature: float
    direction_curvature: float
    iteration: int
    initial_gradient_norm: float
    energies: list = field(default_factory=list)
    gradient_norms: list = field(default_factory=list)
    rng_state: str = ""

    @property
    def energy(self):
        return self.energies[-1]

    @property
    def relative_gradient_norm(self):
        if self.initial_gradient_norm == 0:
            return 0.0
        return self.gradient_norms[-1] / self.initial_gradient_norm


@dataclass
class OptimizeResult:
    """Outcome of ``minimize``: final points, why it stopped, and the history."""

    points: np.ndarray
    status: str
    message: str
    iterations: int
    energy: float
    relative_gradient_norm: float
    energies: np.ndarray
    gradient_norms: np.ndarray
    seconds: float
    state: CGState

    @property
    def success(self):
        return self.status in ("converged", "settled", "max_iterations", "time_limit")


def initial_state(objective, manifold, points):
    """Energy, gradient and the steepest-descent direction at the starting points."""
    objective.set_points(points)
    gradient = manifold.riesz(points, objective.gradient())
    curvature = float(objective.hessian_gram([gradient])[0, 0])
    norm = manifold.norm(points, gradient)
    return CGState(
        points=points,
        gradient=gradient,
        direction=-gradient,
        gradient_curvature=curvature,
        direction_curvature=curvature,
        iteration=0,
        initial_gradient_norm=norm,
        energies=[objective.energy()],
        gradient_norms=[norm],
    )


def cg_step(objective, manifold, state, restart_every, safeguard=False, beta="hestenes-stiefel"):
    """One CG iteration; returns the next state, or ``None`` if no descent step exists.

    Newton step ``alpha = -<d, h> / <d, H d>``, then the next direction ``d' = -h' + beta d~`` by the rule
    ``beta`` (one of ``BETAS``, see the module's docstring) with the transported direction ``d~``; restart with
    ``-h'`` when ``d'`` is not a descent direction. With ``safeguard`` a step that raises the energy is halved
    (up to 30 times) before it is taken.
    """
    points, gradient = state.points, state.gradient
    direction, curvature = state.direction, state.direction_curvature
    if not curvature > 0:
        direction, curvature = -gradient, state.gradient_curvature
        if not curvature > 0:
            return None
    step = -manifold.inner(points, direction, gradient) / curvature * direction
    for _ in range(31 if safeguard else 1):
        new_points = manifold.retract(points, step)
        objective.set_points(new_points)
        if not safeguard or objective.energy() <= state.energy * (1 + 1e-12):
            break
        step = step / 2
    else:
        return None
    new_gradient = manifold.riesz(new_points, objective.gradient())
    moved = manifold.transport(points, step, direction)
    iteration = state.iteration + 1
    restart = bool(restart_every) and iteration % restart_every == 0
    if beta == "daniel":
        new_direction, curvatures = _daniel(objective, manifold, new_points, new_gradient, moved, restart)
    else:
        moved_gradient = manifold.transport(points, step, gradient)
        new_direction, curvatures = _hestenes_stiefel(
            objective, manifold, new_points, new_gradient, moved, moved_gradient, restart
        )
    return replace(
        state,
        points=new_points,
        gradient=new_gradient,
        direction=new_direction,
        gradient_curvature=curvatures[0],
        direction_curvature=curvatures[1],
        iteration=iteration,
        energies=state.energies + [objective.energy()],
        gradient_norms=state.gradient_norms + [manifold.norm(new_points, new_gradient)],
    )


def _daniel(objective, manifold, points, gradient, moved, restart):
    """Daniel's direction and ``(<h, H h>, <d, H d>)`` from the Hessian's form on ``gradient`` and ``moved``."""
    gram = objective.hessian_gram([gradient, moved])
    beta = gram[0, 1] / gram[1, 1] if gram[1, 1] > 0 else 0.0
    direction = -gradient + beta * moved
    curvature = gram[0, 0] - 2 * beta * gram[0, 1] + beta**2 * gram[1, 1]
    if restart or not manifold.inner(points, direction, gradient) < 0:
        direction, curvature = -gradient, gram[0, 0]
    return direction, (float(gram[0, 0]), float(curvature))


def _hestenes_stiefel(objective, manifold, points, gradient, moved, moved_gradient, restart):
    """Hestenes-Stiefel's direction (``beta >= 0``) and ``(0, <d, H d>)``: the form on the new direction only.

    Steepest descent, with ``(<h, H h>, <h, H h>)``, on a restart, for ``beta = 0``, and where the direction is
    not a descent direction or has no positive curvature (possible with the full Hessian).
    """
    change = gradient - moved_gradient
    denominator = manifold.inner(points, moved, change)
    beta = max(manifold.inner(points, gradient, change) / denominator, 0.0) if denominator > 0 else 0.0
    if beta > 0 and not restart:
        direction = -gradient + beta * moved
        if manifold.inner(points, direction, gradient) < 0:
            curvature = float(objective.hessian_gram([direction])[0, 0])
            if curvature > 0:
                return direction, (0.0, curvature)
    steepest = float(objective.hessian_gram([gradient])[0, 0])
    return -gradient, (steepest, steepest)


def time_left(time_limit, started):
    """Seconds left of ``time_limit`` since ``started`` (a ``time.perf_counter()`` reading), at least 0; None
    without a limit."""
    return None if time_limit is None else max(time_limit - (time.perf_counter() - started), 0.0)


def minimize(
    objective,
    manifold,
    points=None,
    *,
    state=None,
    tol=1e-3,
    max_iterations=1000,
    time_limit=None,
    restart_every=None,
    safeguard=False,
    beta="hestenes-stiefel",
    settle=None,
    callback=None,
):
    """Minimise ``objective`` over point sets on ``manifold`` by nonlinear CG.

    Parameters
    ----------
    objective : Discrepancy
    manifold : Torus or Sphere
    points : numpy.ndarray, optional
        Starting points (ignored when ``state`` is given).
    state : CGState, optional
        A saved state to continue from (checkpoint resume).
    tol : float
        Stop when ``|grad E| / |grad E_0| <= tol``.
    max_iterations : int
        Total iteration count at which to stop (counting iterations done before a resume).
    time_limit : float, optional
        Seconds after which to stop (checked after each iteration).
    restart_every : int, optional
        Restart with steepest descent every this many iterations (default: never, besides the
        automatic restarts when the direction is not a descent direction).
    safeguard : bool
        Halve steps that would raise the energy (default off: the paper's method takes every Newton step).
    beta : {"hestenes-stiefel", "daniel"}
        The rule for the next direction (see the module's docstring); "daniel" is the paper's.
    settle : float, optional
        Stop ("settled") when the last ``SETTLE_WINDOW`` iterations lowered the energy by less than this fraction
        of it (default: never).
    callback : callable, optional
        ``callback(state)`` after the start and every iteration; returning True stops the run.

    Returns
    -------
    OptimizeResult
    """
    started = time.perf_counter()
    if state is None:
        state = initial_state(objective, manifold, points)
    status = None
    if callback is not None and callback(state):
        status = "stopped"
    while status is None:
        status = _stop_reason(state, tol, settle, max_iterations, time_limit, time.perf_counter() - started)
        if status is not None:
            break
        following = cg_step(objective, manifold, state, restart_every, safeguard, beta)
        if following is None:
            status = "no_descent"
            break
        state = following
        if callback is not None and callback(state):
            status = "stopped"
    return _result(state, status, time.perf_counter() - started)


def _stop_reason(state, tol, settle, max_iterations, time_limit, elapsed):
    if state.relative_gradient_norm <= tol:
        return "converged"
    if settle and len(state.energies) > SETTLE_WINDOW:
        earlier, now = state.energies[-1 - SETTLE_WINDOW], state.energies[-1]
        if earlier - now < settle * abs(now):
            return "settled"
    if state.iteration >= max_iterations:
        return "max_iterations"
    if time_limit is not None and elapsed >= time_limit:
        return "time_limit"
    return None


_MESSAGES = {
    "converged": "relative gradient norm {rel:.3g} <= tol after {it} iterations",
    "settled": f"energy settled after {{it}} iterations (less than the settle fraction gained over the last "
    f"{SETTLE_WINDOW}; relative gradient norm {{rel:.3g}})",
    "max_iterations": "reached {it} iterations (relative gradient norm {rel:.3g})",
    "time_limit": "time limit reached after {it} iterations (relative gradient norm {rel:.3g})",
    "stopped": "stopped on request after {it} iterations (relative gradient norm {rel:.3g})",
    "no_descent": "no descent direction with positive curvature after {it} iterations",
}


def _result(state, status, seconds):
    message = _MESSAGES[status].format(it=state.iteration, rel=state.relative_gradient_norm)
    return OptimizeResult(
        points=state.points,
        status=status,
        message=message,
        iterations=state.iteration,
        energy=state.energy,
        relative_gradient_norm=state.relative_gradient_norm,
        energies=np.asarray(state.energies),
        gradient_norms=np.asarray(state.gradient_norms),
        seconds=seconds,
        state=state,
    )
