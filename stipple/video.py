"""Stippled video: every frame's dots warm-started from the previous frame's, so that dot i stays dot i.

Frame 0 is a cold run, the same as ``stipple torus`` makes of that frame. Every later frame starts from the
previous frame's points and makes at most ``frame_iterations`` CG iterations on its own problem (in the same
density-scaled metric, without the spread step) moving only the dots near a change (``free_dots``). The other dots
are pinned (``PinnedTorus``): left free, one CG step spreads a local change over the whole picture (M = 20000:
still dots moved 0.25 of their spacing per frame), and the still parts of the video would boil. Then, where the
darkness changed at all, a correction moves all dots by smooth deformations: one field chosen by CG on the
frame's whole objective (``WARM_DEFORMATION``, ``stipple.deformation``), then CG on the plain ``E_N`` of low
bandwidths (``WARM_LEVELS``). They bring the ink a moving object needs from wherever it is and fix the low and
middle frequencies a viewer sees, and leave the still dots' local arrangement as it is. After a scene cut
(``frame_change`` above ``CUT``) the dots of the changed parts make as many iterations as a cold run. The
measurements that chose these settings are in docs/video.md.
"""

import time
from dataclasses import dataclass, replace
from functools import partial

import numpy as np
from scipy.ndimage import distance_transform_edt

from .deformation import deform
from .errors import StippleError
from .halftone import (
    check_bandwidth,
    check_integer,
    correct_low_frequencies,
    correction_bandwidth,
    even_at_least_2,
    gradient_norm,
    iid_gradient_norm,
    run,
)
from .io.video_checkpoint import frame_fingerprint
from .manifolds import PinnedTorus
from .sampling import pixel_indices
from .torus import DEFAULT_EPSILON, default_bandwidth, periodic_blur, torus_problem
from .video_inks import Inks
from .video_keeper import FrameKeeper, checkpoint_settings

# Warm frames, in the density-scaled metric: FRAME_ITERATIONS before the deformation (WARM_DEFORMATION's 4, then
# WARM_POLISH) leave the bench's clips and a light page with small dark blobs within 2.2 dB of the median of three
# stills at sigma 4 px in 0.27-0.29 of a cold frame's time; 8 and 8 left the page 4.6 dB below (docs/video.md).
FRAME_ITERATIONS = 12
# The deformation shifts a moving object's dots as a whole, and where they meet the freed dots it leaves gaps: a
# dark disc moving down 5 px a frame came out with white holes (its lightest pixel 0.65-0.80 for 0.05, blurred at
# 1 px 0.16-0.21 against a cold run's 0.07). WARM_POLISH pinned iterations after the deformation, before the low
# bandwidth's level, close them (12 + 4: 0.08-0.10) at the same cost as 16 before it.
WARM_POLISH = 4
# A warm frame moves the dots within FREE_MARGIN dot spacings of a change in darkness above CHANGE (blurred at one
# spacing, against the darkness the dots there were placed for); 8-bit noise and compression stay below it.
CHANGE = 0.02
FREE_MARGIN = 3.0
# After the pinned phase every warm frame whose darkness changed is corrected over all dots, in two steps. First
# WARM_DEFORMATION = (factor, iterations): CG moves every dot by one smooth displacement field of bandwidth N / factor
# to lower the frame's whole objective (``stipple.deformation``): the middle frequencies that the pinned iterations
# leave (a fade: 3-5 times a cold run's error at 12-24 cycles per image), without stirring the high ones as the
# plain E_N at N / 3 or N / 4 did (docs/video.md). In the density-scaled metric 4 of its iterations instead of 8.
WARM_DEFORMATION = (4, 4)
# A colour video's joint problem stays in the flat metric (``Inks.problem``), where 8 were measured.
COLOUR_DEFORMATION = (4, 8)
# Then, for each (factor, iterations), CG on the plain E_N at N / factor over all dots: the lowest frequencies.
# Without the two, the ink a moving object needs came only from the freed dots around it (a light halo ahead of
# a moving disc, E_N at N = 128 2.5 x a cold run's); the deformation without this level left the photo clips
# 8-10 dB below a cold run at sigma 4 px; a level at N / 12 after it changed nothing.
WARM_LEVELS = ((5, 6), (6, 10))
# Colour frames skip them: each ink's dots followed their own term, and inks slid onto each other (45-130 dots in
# coincident pairs a frame); the deformation moves all dots by one field (docs/video.md, "Colour video").
COLOUR_WARM_LEVELS = ()
# A scene cut: the darkness, blurred at one dot spacing, changed by more than CUT on average over the frame (a cut
# between two photos: 0.15; a pan, a fade, a moving object: at most 0.012 per frame). The freed dots then make up
# to ``iterations`` CG iterations under the cold run's stopping rule, not ``frame_iterations``.
CUT = 0.05
# After a cut the freed dots rearrange completely: only those within CUT_MARGIN spacings of a change are freed
# (FREE_MARGIN let the still dots two to three spacings from a cut move 4.8 spacings at the 95th percentile).
CUT_MARGIN = 1.0


@dataclass
class VideoSettings:
    """What defines a stippled video's optimisation (the keywords of ``torus_problem`` and ``halftone.run``).

    ``palette`` (a separation or pens, ``stipple.colour.separate``; None: gray frames), ``black`` and
    ``union_weight`` make a colour video: frames are RGB, one class of dots per ink (``stipple.colour``).
    ``init`` and ``iterations`` are frame 0's (its cold run) and a scene cut's; ``frame_iterations`` caps every
    other frame's warm-started run, which moves the dots within ``free_margin`` spacings of a change in darkness
    above ``change`` (``free_dots``). ``correct``: the low-frequency correction, of frame 0 and of every warm frame
    whose darkness changed. ``tol``, ``settle``, ``time_limit``, ``safeguard`` and ``beta`` apply to every frame.
    ``placement``: the density the dots are placed by as a function of the frame's (a colour frame's: of its
    inks' together, each ink keeping its share), e.g. clipped at a pen's reach
    (``stipple.pipelines.pen.placement_density``); None: the frame's own.
    """

    n_points: int
    bandwidth: object = None
    backend: str = "ducc0"
    threads: object = None
    epsilon: float = DEFAULT_EPSILON
    hessian: str = "gauss-newton"
    near_field: bool = True
    seed: int = 0
    init: object = "stratified"
    tol: float = 1e-4
    settle: object = None
    iterations: int = 2000
    frame_iterations: int = FRAME_ITERATIONS
    change: float = CHANGE
    free_margin: float = FREE_MARGIN
    time_limit: object = None
    correct: bool = True
    safeguard: bool = False
    beta: str = "hestenes-stiefel"
    palette: object = None
    black: float = 1.0
    union_weight: float = 1.0
    placement: object = None


@dataclass
class Frame:
    """One finished frame: its number in the source, its dots (unit coordinates, row i is dot i), the density
    ``w`` they were placed from (what a tone-true drawing reproduces), and how it was made (``replayed``: read back
    from a checkpoint, not optimised). A colour video's frame also has its ``inks``, ``(name, colour, slice)``
    with ``points[slice]`` the ink's dots (the same in every frame), and its RGB ``picture``; ``density`` is then
    the inks' densities, ``(K, H, W)``."""

    index: int
    points: object
    density: object
    warm: bool
    replayed: bool
    iterations: int = 0
    energy: float = 0.0
    seconds: float = 0.0
    inks: tuple = ()
    picture: object = None


@dataclass
class VideoResult:
    """``status`` "finished" or "stopped" (by ``stop``), a one-line ``message``, the frames finished and how many
    of them this run optimised, and the seconds of frame 0's cold run and of the warm frames on average."""

    status: str
    message: str
    frames: int
    optimised: int
    seconds: float
    cold_seconds: object = None
    warm_seconds: object = None


def stipple_video(
    frames,
    settings,
    *,
    on_frame=None,
    stop=None,
    checkpoint=None,
    resume=False,
    checkpoint_seconds=None,
    checkpoint_frames=None,
    identity=None,
    key=None,
):
    """Stipple a sequence of densities with the same dots, each frame warm-started from the previous one.

    Parameters
    ----------
    frames : iterable of (int, numpy.ndarray)
        ``(index, w)`` per frame, in order, every ``w`` of the same shape (``stipple.io.video.FrameSource``).
    settings : VideoSettings
    on_frame : callable, optional
        ``on_frame(Frame)`` after every finished frame (also those replayed from a checkpoint), in order.
    stop : callable, optional
        ``stop(state)`` is shown every CG state; True stops the run: the frame under way is dropped and the
        result's status is "stopped".
    checkpoint : path, optional
        Save every finished frame's dots there (atomically) every ``checkpoint_seconds`` or ``checkpoint_frames``
        and when the run ends. An existing file is refused unless ``resume``.
    resume : bool
        Replay the checkpoint's frames (their densities must match) and go on from the last one.
    identity : dict, optional
        More settings that define the run (the density's transfer, the frame selection); with the problem's,
        a checkpoint must match them all.
    key : (numpy.ndarray, numpy.ndarray), optional
        ``(points, w)``: a key frame's dots and darkness. The first frame is then warm-started from them, as if
        it followed the key frame: a long clip split into chunks, each started from one shared key frame,
        keeps the still dots of every chunk where the key frame put them (docs/video.md).

    Returns
    -------
    VideoResult
    """
    started = time.perf_counter()
    check_integer("frame iterations", settings.frame_iterations, 0, 10**6)
    if key is not None:
        identity = {**(identity or {}), "key": frame_fingerprint(np.concatenate([np.ravel(k) for k in key]))}
    keeper = FrameKeeper(
        checkpoint, checkpoint_settings(settings, identity), checkpoint_seconds, checkpoint_frames, resume
    )
    bandwidth = None if settings.bandwidth is None else check_bandwidth(settings.bandwidth)  # -N 0 meant the default
    timings, status, position = [], "finished", -1
    reference, free = (None, None) if key is None else (key[1], None)
    previous, before = (None, None) if key is None else key
    inks = None if settings.palette is None else Inks(settings, None if key is None else key[1])
    for position, (index, picture) in enumerate(frames):
        try:
            weights = inks.densities(picture) if inks is not None else _placed(picture, settings.placement)
        except StippleError as error:  # a colour frame's separation (a blank frame) says which frame
            raise StippleError(f"frame {index}: {error}") from None
        if not np.any(np.asarray(weights) > 0):
            raise StippleError(
                f"frame {index} is blank (all white): there is nothing to place dots on; leave it out "
                "(--start/--stop/--step) or cut the clip there"
            )
        if bandwidth is None:
            bandwidth = default_bandwidth(settings.n_points, weights.sum(axis=0) if inks is not None else weights)
        change = frame_change(before, weights, settings.n_points)
        if previous is not None:
            margin = min(settings.free_margin, CUT_MARGIN) if change > CUT else settings.free_margin
            free, reference = free_dots(previous, reference, weights, replace(settings, free_margin=margin))
        saved = keeper.replay(position, index, weights)
        frame = None if saved is None else Frame(index, saved, weights, position > 0, True)
        if frame is None:
            frame = _optimise(weights, index, previous, free, bandwidth, settings, stop, change, inks)
            if frame is None:
                status = "stopped"
                break
            timings.append(frame.seconds)
            keeper.add(frame, weights)
        if inks is not None:
            frame = replace(frame, inks=inks.layers, picture=picture)
        if on_frame is not None:
            on_frame(frame)
        previous, before = frame.points, weights
        reference = weights if reference is None else reference
    keeper.finish(status, position + 1)
    return _result(status, keeper.count, timings, time.perf_counter() - started, cold_first=key is None)


def free_dots(points, reference, weights, settings):
    """The dots a warm frame moves, and the darkness each pixel's dots are then placed for.

    Parameters
    ----------
    points : numpy.ndarray
        The previous frame's dots, ``(M, 2)`` in unit coordinates.
    reference : numpy.ndarray
        The darkness the dots at each pixel were last placed for, ``(H, W)``.
    weights : numpy.ndarray
        This frame's darkness, ``(H, W)``.
    settings : VideoSettings
        ``n_points``, ``change`` and ``free_margin``.

    Returns
    -------
    free : numpy.ndarray of bool, shape (M,)
        Dots within ``free_margin`` mean dot spacings (distances wrap around, as on the torus) of a pixel whose
        darkness differs from ``reference`` by more than ``change``, both as it is and blurred at one spacing
        (the blur keeps 8-bit and compression noise out; the pixel's own change keeps a large change elsewhere
        from spilling into a still part through the blur). A colour video's ``(K, H, W)`` inks: any ink's.
    reference : numpy.ndarray
        ``weights`` within that margin, ``reference`` elsewhere.
    """
    rows, columns = weights.shape[-2:]
    spacing = np.sqrt(2 * rows * columns / (np.sqrt(3) * settings.n_points))
    difference = weights - reference
    changed = (np.abs(_blur(difference, spacing)) > settings.change) & (np.abs(difference) > settings.change)
    changed = changed.any(axis=0) if changed.ndim == 3 else changed
    pad = int(np.ceil(settings.free_margin * spacing)) + 1
    pr, pc = min(pad, rows), min(pad, columns)
    distance = distance_transform_edt(np.pad(~changed, ((pr, pr), (pc, pc)), mode="wrap"))[
        pr : pr + rows, pc : pc + columns
    ]
    near = changed.any() & (distance <= settings.free_margin * spacing)
    return near[pixel_indices(points, (rows, columns))], np.where(near, weights, reference)


def frame_change(before, weights, n_points):
    """The mean absolute change of the darkness from ``before`` to ``weights``, both blurred at the mean spacing of
    ``n_points`` dots (periodically); 0 for identical frames, infinite without ``before``."""
    if before is None:
        return float("inf")
    if np.array_equal(before, weights):
        return 0.0
    rows, columns = weights.shape[-2:]
    spacing = np.sqrt(2 * rows * columns / (np.sqrt(3) * n_points))
    blurred = np.abs(_blur(weights - before, spacing))
    return float((blurred.sum(axis=0) if blurred.ndim == 3 else blurred).mean())


def _blur(values, sigma):
    """A periodic Gaussian blur of ``sigma`` pixels of an ``(H, W)`` array or of each of a ``(K, H, W)`` stack
    (``stipple.torus.periodic_blur``: through the FFT when wide)."""
    if np.ndim(values) == 2:
        return periodic_blur(values, sigma)
    return np.stack([periodic_blur(layer, sigma) for layer in values])


def _optimise(weights, index, previous, free, bandwidth, settings, stop, change=float("inf"), inks=None):
    """Frame ``index``'s dots: a cold run without ``previous`` points, else warm-started from them (``_warm``);
    None if ``stop`` stopped it."""
    started = time.perf_counter()
    problem = _problem(weights, bandwidth, settings, inks)
    warm = previous is not None
    if warm:
        result = _warm(problem, previous, free, settings, stop, change)
    else:
        result = run(
            problem,
            init=settings.init,
            iterations=settings.iterations,
            correct=settings.correct,
            **_run_options(settings, stop),
        )
    if result is None or result.status == "stopped":
        return None
    return Frame(
        index, result.points, weights, warm, False, result.iterations, result.energy, time.perf_counter() - started
    )


def _warm(problem, previous, free, settings, stop, change):
    """A warm frame: at most ``frame_iterations`` CG iterations moving the ``free`` dots only (the others pinned;
    after a scene cut, ``change`` above ``CUT``, up to ``iterations``), then, where the darkness changed at all,
    the correction over all dots (``_correct``)."""
    # Without the spread step, which a warm frame cannot pay for: it needs CG iterations over all dots and the
    # correction after it (docs/video.md); its pinned dots, and a colour frame's inks on each other, stay put.
    options = {**_run_options(settings, stop), "spread": False, "part": False}
    changed = change > 0
    if not free.any() and not (changed and settings.correct):
        return run(problem, init=previous, iterations=0, correct=False, **options)
    pinned = replace(problem, manifold=PinnedTorus(problem.manifold, free))
    if change > CUT and free.any():
        options["tol"] = _cut_tol(problem, pinned, previous, settings)
    result = run(
        pinned,
        init=previous,
        iterations=(settings.iterations if change > CUT else settings.frame_iterations) if free.any() else 0,
        correct=False,
        **options,
    )
    if result.status == "stopped" or not (changed and settings.correct):
        return result
    polish = partial(_polish, pinned, options) if free.any() else None
    return _correct(problem, result, settings, stop, polish)


def _polish(pinned, options, points):
    """The freed dots' ``WARM_POLISH`` iterations after the deformation (the others pinned)."""
    return run(pinned, init=points, iterations=WARM_POLISH, correct=False, **options)


def _cut_tol(problem, pinned, previous, settings):
    """A scene cut's ``tol``, relative to its warm start's gradient norm as ``run`` takes it, that stops where a
    cold run of the frame would: at ``settings.tol`` of the gradient norm at i.i.d. samples of the frame. Relative
    to the warm start's own, far smaller norm, a colour pan's cut frames ran 1150-1670 iterations (a cold frame
    738) and took 1.6 times a cold frame."""
    start = gradient_norm(pinned, previous)
    if not start > 0:
        return settings.tol
    iid = iid_gradient_norm(problem, np.random.default_rng(settings.seed))
    return min(settings.tol * iid / start, 0.5)


def _correct(problem, result, settings, stop, polish=None):
    """A warm frame's correction over all dots: the smooth deformation (``WARM_DEFORMATION``), then ``polish``
    (the freed dots' ``WARM_POLISH`` iterations, if given), then the plain ``E_N`` levels (``WARM_LEVELS``; none
    for colour, ``COLOUR_WARM_LEVELS``); the result counts their iterations."""
    factor, iterations = WARM_DEFORMATION if settings.palette is None else COLOUR_DEFORMATION
    shown = None if stop is None else (lambda _: stop(result.state))
    points, deformed = deform(
        problem.objective,
        problem.manifold.scale,
        result.points,
        even_at_least_2(correction_bandwidth(problem) / factor),
        iterations,
        time_limit=settings.time_limit,
        callback=shown,
    )
    if deformed.status == "stopped":
        return replace(result, status="stopped")
    result = replace(result, points=points, iterations=result.iterations + deformed.iterations)
    if polish is not None:
        polished = polish(points)
        if polished.status == "stopped":
            return replace(result, status="stopped")
        result = replace(result, points=polished.points, iterations=result.iterations + polished.iterations)
    levels = WARM_LEVELS if settings.palette is None else COLOUR_WARM_LEVELS
    result = correct_low_frequencies(problem, result, settings.time_limit, stop, levels=levels)
    if any(level.status == "stopped" for level in result.corrections):
        return replace(result, status="stopped")
    return replace(result, iterations=result.iterations + sum(level.iterations for level in result.corrections))


def _problem(weights, bandwidth, settings, inks):
    """A frame's problem: ``torus_problem`` of the darkness, or a colour video's ``Inks.problem``."""
    if inks is not None:
        return inks.problem(weights, bandwidth)
    return torus_problem(
        weights,
        settings.n_points,
        bandwidth,
        backend=settings.backend,
        threads=settings.threads,
        epsilon=settings.epsilon,
        hessian=settings.hessian,
        near_field=settings.near_field,
        # Every frame in the density-scaled metric, as a still is solved: in the flat metric, 600 dots on a photo
        # fell 2-5.5 dB below a still at sigma 4 px in frame 0, and on held-out clips the warm frames stayed 2-13 dB
        # below (a dark pan, a wide clip, light backgrounds with small dark blobs; docs/video.md).
        precondition=True,
    )


def _run_options(settings, stop):
    """``halftone.run``'s keywords that every frame shares."""
    return {
        "seed": settings.seed,
        "tol": settings.tol,
        "time_limit": settings.time_limit,
        "safeguard": settings.safeguard,
        "beta": settings.beta,
        "settle": settings.settle,
        "callback": stop,
    }


def _placed(weights, placement):
    return weights if placement is None else placement(weights)


def _result(status, frames, timings, seconds, cold_first=True):
    if frames == 0 and status == "finished":
        raise StippleError("no frame was stippled")
    cold = timings[0] if cold_first and timings and len(timings) == frames else None
    warm = timings[1:] if cold is not None else timings
    average = sum(warm) / len(warm) if warm else None
    message = f"{frames} frame" + ("" if frames == 1 else "s")
    if cold is not None:
        message += f"; frame 0 (cold) {cold:.2f} s"
    if average is not None:
        message += f"; warm-started frames {average:.2f} s each"
    if status == "stopped":
        message = f"stopped after {message}"
    return VideoResult(status, message, frames, len(timings), seconds, cold, average)
