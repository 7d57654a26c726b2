"""The shared driver: a problem (manifold + objective + sampler) and a CG run on it."""

import json
import os
import time
from dataclasses import dataclass, fields, replace

import numpy as np

from . import allocator
from .checks import MAX_ITERATIONS, check_hooks, check_integer, check_positive, is_real
from .errors import StippleError
from .multilevel import coarse_to_fine
from .optimize import BETAS, OptimizeResult, initial_state, minimize, time_left
from .sampling import part_coincident

MAX_POINTS = 20_000_000
MAX_BANDWIDTH = 8192
INITS = ("stratified", "density", "uniform")
# The final low-frequency correction: for each (factor, iterations) in turn, that many CG iterations on the plain
# E_N at bandwidth N / factor; under a time limit at most COARSE_TIME_SHARE of it in all (README, Defaults).
COARSE_LEVELS = ((6, 5), (12, 20))
COARSE_TIME_SHARE = 0.04
# Under a time limit, the coarse-to-fine start takes at most this share of it.
LEVELS_TIME_SHARE = 0.25
# Default ``settle``: stop when 20 iterations gain less than this fraction of the energy (README, Defaults).
# With the spread step (``stipple.spread``) 2e-3: the portrait stops after 117 iterations (146 at 1.2e-3 without
# the step) and the dark rocket after 108 (139), both with p01 above that of the flat run's stop after 166 and 150
# iterations; without the step, 2e-3 stops them below it (docs/performance.md).
DEFAULT_SETTLE = 2e-3
# ... and the previous version's, for the flat metric from the stratified start (``precondition=False``): the
# density-scaled metric gains more per iteration at the same quality, so the same fraction stops it earlier than
# the p01 of the flat run's stop (the portrait: 133 iterations and p01 0.7375 at 1.5e-3, 146 and 0.7431 at
# 1.2e-3, against 166 and 0.7398 with the flat metric).
FLAT_SETTLE = 1.5e-3


@dataclass
class Problem:
    """A halftoning problem ready to optimise.

    ``objective`` is what CG minimises; ``discrepancy`` its transform part (the whole objective without a near
    field), which evaluation uses for ``E_N``. ``sample(rng, count)`` draws i.i.d. points from the density and
    ``stratified(rng, count)``, where the domain has one, points stratified over it; ``settings`` are the values
    that define the problem (compared when a checkpoint is resumed). ``coarse(bandwidth)``, where the domain has
    one, is the same density's plain ``E_N`` problem at a lower bandwidth, for the final low-frequency correction;
    ``settle`` the default of ``run``'s ``settle`` for it (0: never). ``level(count)`` and ``split(points,
    count)``, where the domain has them, are the same problem with ``count`` dots and the transfer of a level's
    points to ``count`` dots, for the coarse-to-fine start (``stipple.multilevel``). ``correction_bandwidth``
    (default: ``bandwidth``) is the N that the correction's levels divide. ``spread(points) -> (points, moved)``,
    where the domain has it, moves the dots closest to their neighbours apart (``stipple.spread``) at the end.
    """

    domain: str
    manifold: object
    objective: object
    discrepancy: object
    n_points: int
    bandwidth: int
    sample: object
    settings: dict
    stratified: object = None
    coarse: object = None
    settle: float = 0.0
    level: object = None
    split: object = None
    correction_bandwidth: int = 0
    spread: object = None


@dataclass
class HalftoneResult(OptimizeResult):
    """An ``OptimizeResult`` (points, status, message, history, final state) and the bandwidth used.

    After a low-frequency correction, ``points``, ``energy`` and ``relative_gradient_norm`` are those of the
    corrected points, while the history and ``state`` are the main run's (a resumed run continues from there);
    ``corrections`` are the correction's own ``OptimizeResult`` per level (their energies are the coarse ``E_N``).
    """

    bandwidth: int = 0
    corrections: tuple = ()


def default_threads():
    """The number of CPUs this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def check_count(n_points):
    return check_integer("number of points", n_points, 1, MAX_POINTS)


def check_threads(threads):
    return check_integer("threads", threads, 1, 1024)


def check_bandwidth(bandwidth):
    return check_integer("bandwidth", bandwidth, 2, MAX_BANDWIDTH, even=True)


def hexagonal_spacing(n_points, area):
    """Distance between neighbours of ``n_points`` dots in hexagonal packing on ``area``."""
    return np.sqrt(2 * area / (np.sqrt(3) * n_points))


def check_memory(needed, what):
    """Refuse a problem whose estimated working memory exceeds what the machine has available."""
    available = allocator.available_memory()
    if needed > available:
        raise StippleError(
            f"{what} needs about {needed / 2**30:.1f} GiB of memory, more than the {available / 2**30:.1f} GiB "
            "available; use fewer points or a smaller bandwidth"
        )


def check_epsilon(epsilon, name="epsilon"):
    if not is_real(epsilon) or not 1e-14 <= epsilon <= 1e-2:
        raise StippleError(f"{name} must be a number in [1e-14, 1e-2], not {epsilon!r}")
    return float(epsilon)


def check_run_options(
    *,
    tol=1e-4,
    time_limit=None,
    settle=None,
    iterations=400,
    beta=BETAS[0],
    seed=0,
    restart_every=None,
    checkpoint_seconds=None,
    checkpoint_iterations=None,
    **_,
):
    """Raise if a stopping, direction, seed or checkpoint setting of ``run`` is out of range (checked before any
    work: a seed of -1 or 1.5 failed in numpy's words, a ``restart_every`` of "a" after the start was made)."""
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise StippleError(f"seed must be a non-negative integer (the same seed gives the same points), not {seed!r}")
    check_positive("tol", tol)
    check_positive("time_limit", time_limit, allow_none=True)
    if restart_every is not None:
        check_integer("restart_every", restart_every, 1, MAX_ITERATIONS)
    check_positive("checkpoint_seconds", checkpoint_seconds, allow_none=True)
    if checkpoint_iterations is not None:
        check_integer("checkpoint_iterations", checkpoint_iterations, 1, MAX_ITERATIONS)
    if settle is not None and (not is_real(settle) or not 0 <= settle < 1):
        raise StippleError(f"settle must be a number in [0, 1), not {settle!r}")
    check_integer("iterations", iterations, 0, MAX_ITERATIONS)
    if beta not in BETAS:
        raise StippleError(f"beta must be one of {', '.join(BETAS)}, not {beta!r}")


def initial_points(problem, init, rng):
    """Starting points: i.i.d. from the density, i.i.d. uniform, or given (checked for shape)."""
    if isinstance(init, str):
        if init not in INITS:
            raise StippleError(f"init must be one of {', '.join(INITS)} or an array, not {init!r}")
        if init == "stratified" and problem.stratified is not None:
            return problem.stratified(rng, problem.n_points)
        if init in ("stratified", "density"):
            return problem.sample(rng, problem.n_points)
        return problem.manifold.random(rng, problem.n_points)
    points = np.asarray(init)
    expected = (problem.n_points, problem.manifold.dimension)
    if points.dtype.kind not in "biuf":
        raise StippleError(f"initial points must be real numbers, not {points.dtype}")
    if points.shape != expected:
        given = f"{points.shape[0]} of {points.shape[1]}" if points.ndim == 2 else f"an array of shape {points.shape}"
        raise StippleError(f"initial points must be M = {expected[0]} points of {expected[1]} coordinates, not {given}")
    points = points.astype(np.float64)
    if not np.all(np.isfinite(points)) or (problem.domain == "sphere" and np.any(np.all(points == 0, axis=1))):
        raise StippleError("initial points contain NaN, infinite or (on the sphere) zero vectors")
    if problem.domain == "sphere":
        # Each vector over its largest entry first: lengths of 1e160 or 1e-320 over- or underflowed the norm.
        points = points / np.max(np.abs(points), axis=1, keepdims=True)
    return problem.manifold.canonical(points)


def run(
    problem,
    *,
    init="stratified",
    seed=0,
    tol=1e-4,
    iterations=2000,
    time_limit=None,
    restart_every=None,
    safeguard=False,
    beta="hestenes-stiefel",
    settle=None,
    callback=None,
    checkpoint=None,
    checkpoint_seconds=None,
    checkpoint_iterations=None,
    resume=False,
    correct=True,
    levels=True,
    spread=True,
    part=True,
):
    """Optimise ``problem`` from ``init``, or resume it from a checkpoint, and collect the result.

    Parameters
    ----------
    problem : Problem
    init : {"stratified", "density", "uniform"} or array
        Starting points: stratified over the density where the domain has such a sampler (the torus: along a
        Hilbert curve through the pixels; default), otherwise and with "density" i.i.d. from the density, i.i.d.
        uniform, or given (internal coordinates). ``tol`` is relative to the gradient norm at the start, and for
        the stratified start to that at i.i.d. density samples, so that it means the same for both.
    seed : int
        Seed of the random start.
    tol, iterations, time_limit, restart_every, safeguard, beta, callback :
        See ``stipple.optimize.minimize``; ``iterations`` counts from the very start of a resumed run.
    settle : float, optional
        Also stop when the last ``SETTLE_WINDOW`` iterations lowered the energy by less than this fraction of it
        (``stipple.optimize.minimize``); default ``problem.settle`` (the torus: ``DEFAULT_SETTLE``); 0: never.
    checkpoint : path, optional
        Save the complete state there (atomically) every ``checkpoint_seconds`` or
        ``checkpoint_iterations``, and when the run ends. An existing file is never overwritten unless
        the run resumes from it.
    resume : bool
        Continue from ``checkpoint`` (refused if it belongs to another problem).
    correct : bool
        Finish with the low-frequency correction (``correct_low_frequencies``) where the problem has a ``coarse``
        version, unless the run made no iteration or was stopped by ``callback``. Under a ``time_limit`` the main
        run leaves ``COARSE_TIME_SHARE`` of it to the correction.
    levels : bool
        With the stratified start, start instead from the coarse-to-fine solution (``stipple.multilevel``)
        where the problem has levels: fewer dots solved first at a lower bandwidth, then split. Under a
        ``time_limit`` it takes at most ``LEVELS_TIME_SHARE`` of it; ``callback`` sees its levels' states.
    spread : bool
        Where the problem has a ``spread`` step, apply it to the main run's points and follow it with
        ``SPREAD_ITERATIONS`` CG iterations (``spread_close_dots``), before the correction; not after a run that
        reached its time limit, made no iteration or was stopped by ``callback``.
    part : bool
        Move a given start's dots that share a place apart first (``part_coincident``): nothing else would. A
        video's warm frames keep theirs (pinned dots stay where they are).
    """
    from .checkpoint import Checkpointer, load_checkpoint

    check_hooks(callback, checkpoint)
    settle = problem.settle if settle is None else settle
    check_run_options(
        tol=tol,
        time_limit=time_limit,
        settle=settle,
        iterations=iterations,
        beta=beta,
        seed=seed,
        restart_every=restart_every,
        checkpoint_seconds=checkpoint_seconds,
        checkpoint_iterations=checkpoint_iterations,
    )
    saver = None
    if checkpoint is not None:
        if not resume and os.path.exists(checkpoint):
            raise StippleError(f"{checkpoint}: checkpoint exists; resume it or remove it first")
        saver = Checkpointer(checkpoint, problem, seconds=checkpoint_seconds, iterations=checkpoint_iterations)
    elif resume:
        raise StippleError("resume needs a checkpoint file")
    started = time.perf_counter()
    if resume:
        state = load_checkpoint(checkpoint, problem)
    else:
        state, start_stopped = _start_state(problem, init, seed, levels, time_limit, callback, part)
        # A start stopped half-way (the coarse levels) is not the uninterrupted run's: nothing to resume from.
        saver = None if start_stopped else saver
    corrects = correct and problem.coarse is not None and correction_bandwidth(problem) >= 4 * max(COARSE_LEVELS)[0]
    main_limit = None
    if time_limit is not None:
        share = 1 - COARSE_TIME_SHARE if corrects else 1.0
        main_limit = max(time_limit * share - (time.perf_counter() - started), 0.0)
    outcome = minimize(
        problem.objective,
        problem.manifold,
        state=state,
        tol=tol,
        max_iterations=iterations,
        time_limit=main_limit,
        restart_every=restart_every,
        safeguard=safeguard,
        beta=beta,
        settle=settle,
        callback=chain_callbacks(saver, callback),
    )
    if saver is not None:
        saver.save(outcome.state)
    result = HalftoneResult(
        **{item.name: getattr(outcome, item.name) for item in fields(outcome)}, bandwidth=problem.bandwidth
    )
    spreads = spread and problem.spread is not None and result.iterations > 0
    if spreads and result.status not in ("stopped", "time_limit"):
        result = spread_close_dots(problem, result, callback=callback)
    if corrects and result.iterations > 0 and result.status != "stopped":
        remaining = time_left(time_limit, started)
        result = correct_low_frequencies(problem, result, remaining, callback)
    return result


def _start_state(problem, init, seed, levels, time_limit, callback, part=True):
    """CG's first state from ``init`` (the coarse-to-fine start for "stratified" where the problem has levels and
    ``levels`` asks for it; given points parted with ``part``), and whether ``callback`` stopped the levels;
    ``tol``'s reference is the gradient norm at i.i.d. samples for the stratified start and a parted one."""
    rng = np.random.default_rng(seed)
    stratified = isinstance(init, str) and init == "stratified" and problem.stratified is not None
    stops, parted = [], 0
    if stratified and levels and problem.level is not None:
        share = None if time_limit is None else time_limit * LEVELS_TIME_SHARE

        def watched(state):
            stops.append(bool(callback(state)))
            return stops[-1]

        start = coarse_to_fine(problem, rng, time_limit=share, callback=None if callback is None else watched)
    else:
        start = initial_points(problem, init, rng)
        if part and not isinstance(init, str):
            start, parted = part_coincident(problem.manifold, start)
    reference = None
    if stratified or parted:
        # A parted start's clumps have a steep gradient: relative to it, tol would stop the run early.
        reference = iid_gradient_norm(problem, rng)
    state = initial_state(problem.objective, problem.manifold, start)
    state.initial_gradient_norm = state.initial_gradient_norm if reference is None else reference
    state.rng_state = json.dumps(rng.bit_generator.state)
    return state, any(stops)


# CG iterations after the spread step (``stipple.spread``), before the low-frequency correction.
SPREAD_ITERATIONS = 3


def spread_close_dots(problem, result, callback=None, iterations=SPREAD_ITERATIONS):
    """Spread the dots closest to their neighbours (``problem.spread``), then ``iterations`` CG iterations from
    there (restarted). Returns ``result`` with those points and their energy; its history and ``state`` stay the
    main run's. ``callback`` is shown the main run's final state and may stop the iterations."""
    points, moved = problem.spread(result.points)
    if moved == 0:
        return result
    after = minimize(
        problem.objective,
        problem.manifold,
        points,
        tol=1e-12,
        max_iterations=iterations,
        callback=None if callback is None else lambda _: callback(result.state),
    )
    return replace(
        result,
        points=after.points,
        energy=after.energy,
        message=f"{result.message}; {moved} close dots spread, then {after.iterations} iterations",
        status="stopped" if after.status == "stopped" else result.status,  # the callback's stop is the run's
    )


def correct_low_frequencies(problem, result, time_limit=None, callback=None, levels=COARSE_LEVELS):
    """Move ``result.points`` by CG on the plain ``E_N`` of ``problem.coarse`` at ``N / factor``, for each
    ``(factor, iterations)`` of ``levels`` in turn (``N``: ``problem.correction_bandwidth`` if set).

    A coarse problem's gradient is a smooth field, so its steps are smooth deformations of the point set that fix
    the frequencies below ``N / (2 factor)``, which every iteration of the main run stirs up again, and leave the
    dots' local arrangement nearly as it is. They also disturb the band just above ``N / (2 factor)``, the more the
    more iterations: the finer level goes first and briefly, the coarser one last. ``time_limit`` is for all
    levels. ``callback`` is shown the main run's final state and may stop the correction. Returns ``result`` with
    the corrected points, the main objective's energy and gradient norm there, and ``corrections``.
    """
    started = time.perf_counter()
    points, corrections, summary = result.points, [], []
    for factor, iterations in levels:
        coarse = problem.coarse(even_at_least_2(correction_bandwidth(problem) / factor))
        remaining = time_left(time_limit, started)
        correction = minimize(
            coarse.objective,
            coarse.manifold,
            points,
            tol=1e-12,
            max_iterations=iterations,
            time_limit=remaining,
            callback=None if callback is None else lambda _: callback(result.state),
        )
        points = correction.points
        corrections.append(correction)
        summary.append(f"{correction.iterations} at N={coarse.bandwidth}")
        if correction.status == "stopped":
            break
    status = "stopped" if corrections and corrections[-1].status == "stopped" else result.status
    if sum(level.iterations for level in corrections) == 0:
        return replace(result, corrections=tuple(corrections), status=status)
    norm = gradient_norm(problem, points)
    initial = result.state.initial_gradient_norm
    return replace(
        result,
        points=points,
        energy=problem.objective.energy(),
        relative_gradient_norm=norm / initial if initial > 0 else 0.0,
        message=f"{result.message}; low-frequency correction: {', '.join(summary)} iterations",
        corrections=tuple(corrections),
        status=status,
    )


def correction_bandwidth(problem):
    """The N that the low-frequency corrections divide: ``problem.correction_bandwidth``, else its bandwidth."""
    return problem.correction_bandwidth or problem.bandwidth


def even_at_least_2(value):
    """``value`` rounded to an even integer, at least 2."""
    return max(2, 2 * int(round(value / 2)))


def iid_gradient_norm(problem, rng):
    """``tol``'s reference where a start is not i.i.d.: the gradient norm at i.i.d. samples of the density (a cold
    run's stratified start, a video's scene cut), so that ``tol`` means what it means from i.i.d. samples."""
    return gradient_norm(problem, problem.sample(rng, problem.n_points))


def gradient_norm(problem, points):
    """Norm of the objective's gradient at ``points`` (leaves the objective there)."""
    problem.objective.set_points(points)
    return problem.manifold.norm(points, problem.manifold.riesz(points, problem.objective.gradient()))


def chain_callbacks(*callbacks):
    """One callback calling each given one in turn; stops when any of them asks to."""
    active = [callback for callback in callbacks if callback is not None]
    if not active:
        return None
    return lambda state: any([callback(state) for callback in active])
