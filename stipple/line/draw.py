"""``draw_line``: the curve optimised in phases, the speed penalty's weight raised until every segment holds."""

import functools
import math
import os
import time

import numpy as np

from ..checkpoint import Checkpointer, saved_settings
from ..errors import StippleError
from ..halftone import chain_callbacks, run
from ..io.images import load_density
from ..torus import check_weights
from .problem import INITIAL_PENALTY, LINE_ITERATIONS, MAX_PHASES, PENALTY_GROWTH, line_problem
from .start import initial_loop


def draw_line(
    image,
    n_vertices,
    length=None,
    bandwidth=None,
    *,
    seed=0,
    init=None,
    tol=1e-4,
    iterations=LINE_ITERATIONS,
    phase_iterations=None,
    constraint_tol=0.01,
    initial_penalty=INITIAL_PENALTY,
    time_limit=None,
    callback=None,
    checkpoint=None,
    checkpoint_seconds=None,
    checkpoint_iterations=None,
    resume=False,
    beta="hestenes-stiefel",
    threads=None,
    epsilon=1e-9,
    backend="ducc0",
    subdivisions=None,
):
    """One closed curve with ``n_vertices`` vertices whose length measure reproduces ``image``.

    Phase 0 runs CG with penalty weight ``initial_penalty`` (in units of ``penalty_scale``) for up to
    ``iterations``; every following phase multiplies it by 8 and runs up to ``phase_iterations`` more (default
    ``iterations // 4``), until the longest segment is within ``constraint_tol`` of ``h = L / M``.

    Parameters
    ----------
    image : array_like of shape (H, W), or a path
        Density (``stipple.load_density``).
    n_vertices : int
    length : float, optional
        Curve length bound L in pixels (default ``default_length``: ``c sqrt(M W H)``, c 0.6-1.1, at most
        1.1 ``sum w / t``, ``t`` the darkest tone).
    bandwidth : int, optional
    init : array_like, optional
        Starting vertices in unit coordinates (default: ``initial_loop``).
    tol, iterations, time_limit, callback, checkpoint, checkpoint_seconds, checkpoint_iterations, resume, beta :
        As for ``stipple.halftone.run``; ``time_limit`` counts over all phases.
    subdivisions : int, optional
        Quadrature nodes per segment (``line_problem``).

    Returns
    -------
    HalftoneResult
        ``points`` (M, 2) in unit coordinates of the image, in path order; ``state`` of the last phase. Also
        ``problem`` and ``penalty`` of the last phase, and ``segment_lengths`` in pixels.
    """
    weights = check_weights(load_density(image) if isinstance(image, (str, os.PathLike)) else image)
    penalty, done = initial_penalty, 0
    if resume and checkpoint is not None:
        penalty = saved_settings(checkpoint).get("penalty", 1.0)
        if isinstance(penalty, bool) or not isinstance(penalty, (int, float)) or not 0 < penalty < float("inf"):
            raise StippleError(f"{checkpoint}: corrupt checkpoint metadata (penalty {penalty!r})")
        done = phases_before(penalty, initial_penalty)
    phase_cap = max(1, iterations // 4) if phase_iterations is None else phase_iterations
    build = functools.partial(
        line_problem,
        weights,
        n_vertices,
        length,
        bandwidth,
        threads=threads,
        epsilon=epsilon,
        backend=backend,
        subdivisions=subdivisions,
    )
    problem = build(penalty=penalty)
    if init is None:
        init = initial_loop(weights, problem.n_points, seed=seed, threads=threads)
    init = problem.manifold.inward(init)
    started = time.perf_counter()
    result = run(
        problem,
        init=init,
        tol=tol,
        iterations=phase_cap if done else iterations,  # a later phase resumed: its own cap, as it first ran
        time_limit=time_limit,
        callback=callback,
        checkpoint=checkpoint,
        checkpoint_seconds=checkpoint_seconds,
        checkpoint_iterations=checkpoint_iterations,
        resume=resume,
        beta=beta,
    )
    phase = {"tol": tol, "iterations": phase_cap, "beta": beta, "callback": callback, "left": MAX_PHASES - done}
    saving = {"path": checkpoint, "seconds": checkpoint_seconds, "iterations": checkpoint_iterations}
    ends = (started, time_limit)
    counts = [result.iterations]
    problem, penalty, result = tighten(build, problem, penalty, result, constraint_tol, phase, saving, ends, counts)
    return finished(result, problem, penalty, started, counts)


def tighten(build, problem, penalty, result, constraint_tol, phase, saving, ends, counts):
    """The later phases: while a segment is off ``h`` by more than ``constraint_tol`` (and the run was neither
    stopped nor out of time), the penalty's weight times ``PENALTY_GROWTH`` and ``phase["iterations"]`` more
    CG iterations from the last points, each phase saving its own checkpoint and appending its iterations to
    ``counts``. Returns the last phase's problem, penalty and result."""
    started, time_limit = ends
    for _ in range(phase["left"]):
        if constraints_hold(problem, result.points, constraint_tol) or result.status == "stopped":
            break
        remaining = None if time_limit is None else time_limit - (time.perf_counter() - started)
        if remaining is not None and remaining <= 0:
            break
        penalty *= PENALTY_GROWTH
        problem = build(penalty=penalty)
        saver = None
        if saving["path"] is not None:
            saver = Checkpointer(saving["path"], problem, seconds=saving["seconds"], iterations=saving["iterations"])
        result = run(
            problem,
            init=result.points,
            tol=phase["tol"],
            iterations=phase["iterations"],
            time_limit=remaining,
            callback=chain_callbacks(saver, phase["callback"]),
            beta=phase["beta"],
        )
        if saver is not None:
            saver.save(result.state)
        counts.append(result.iterations)
    return problem, penalty, result


def phases_before(penalty, initial_penalty):
    """How many phases came before the one of weight ``penalty`` (a checkpoint's): each multiplied the weight by
    ``PENALTY_GROWTH``. A resumed later phase ran with the first phase's cap and all ``MAX_PHASES`` after it, and
    ended elsewhere than the run it continued (a hostile review)."""
    return max(0, round(math.log(penalty / initial_penalty) / math.log(PENALTY_GROWTH)))


def finished(result, problem, penalty, started, counts):
    """The last phase's result with the whole run's seconds, its problem and penalty, the segment lengths in
    pixels, and the vertices in unit coordinates of the image; with several phases its message counts all their
    iterations (``counts``), not only the last one's."""
    result.seconds = time.perf_counter() - started
    if len(counts) > 1:
        result.message = f"{sum(counts)} iterations in {len(counts)} phases, the last: {result.message}"
    result.problem, result.penalty = problem, penalty
    problem.speed.set_points(result.points)
    result.segment_lengths = problem.speed.segment_lengths() * problem.pixels_per_unit
    result.points = problem.manifold.outward(result.points)
    return result


def constraints_hold(problem, points, constraint_tol):
    """Every segment within ``(1 ± constraint_tol) h``."""
    problem.speed.set_points(points)
    return np.abs(problem.speed.segment_lengths() / problem.step - 1).max() <= constraint_tol


def line_points(points):
    """Vertices in the unit rectangle (``Rectangle`` keeps them there; a given ``init`` is clipped on entry)."""
    return np.clip(points, 0.0, 1.0)
