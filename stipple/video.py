"""Stippled video: every frame's dots warm-started from the previous frame's, so that dot i stays dot i.

Frame 0 is a cold run, the same as ``stipple torus`` makes of that frame. Every later frame starts from the
previous frame's points and makes at most ``frame_iterations`` CG iterations on its own problem moving only the
dots near a change: within ``free_margin`` spacings of a pixel whose darkness differs by more than ``change`` from
what the dots there were last placed for, both as it is and blurred at one spacing (``free_dots``). The other dots
are pinned (``PinnedTorus``): left free, one CG step spreads a local change over the whole picture (M = 20000:
still dots moved 0.25 of their spacing per frame), and the still parts of the video would boil. Then, where the
darkness changed at all, the low-frequency correction runs over all dots (``WARM_LEVELS``): smooth deformations
that bring the ink a moving object needs from wherever it is, and leave the still dots' local arrangement as it
is (they move a median 0.01-0.02 spacings). After a scene cut (``frame_change`` above ``CUT``) the dots of the
changed parts make as many iterations as a cold run. The measurements that chose these settings are in
docs/video.md.
"""

import os
import time
from dataclasses import dataclass, replace

import numpy as np
from scipy.ndimage import distance_transform_edt, gaussian_filter

from .colour import palette_label
from .errors import StippleError
from .halftone import check_integer, correct_low_frequencies, run
from .io.video import frame_fingerprint, load_video_checkpoint, save_video_checkpoint
from .manifolds import PinnedTorus
from .sampling import pixel_indices
from .torus import DEFAULT_EPSILON, default_bandwidth, torus_problem
from .video_inks import Inks

# Warm frames: 20 CG iterations reached E_N within 1-2 % of a cold run of each frame on the test clips, where 10
# left 4-12 % and the dots' moves in still regions were the same (docs/video.md).
FRAME_ITERATIONS = 20
# A warm frame moves the dots within FREE_MARGIN dot spacings of a change in darkness above CHANGE (blurred at one
# spacing, against the darkness the dots there were placed for); 8-bit noise and compression stay below it.
CHANGE = 0.02
FREE_MARGIN = 3.0
# After the pinned phase every warm frame whose darkness changed makes a low-frequency correction over all dots:
# for each (factor, iterations), CG on the plain E_N at N / factor. Without it the ink a moving object needs came
# only from the freed dots around it (a light halo ahead of a moving disc, E_N at N = 128 2.5 x a cold run's);
# the cold run's two levels (N / 6, N / 12) left a pan 7 dB below a cold run at sigma 4 px, a level at N / 3 brings
# it within 3 dB; a level at N / 12 changed nothing at N = 214 and at N = 48 (4 modes) moved still dots 0.05-0.11
# spacings a frame (docs/video.md).
WARM_LEVELS = ((3, 5), (6, 10))
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
    keeper = _Keeper(checkpoint, _defining(settings, identity), checkpoint_seconds, checkpoint_frames, resume)
    bandwidth, timings, status, position = settings.bandwidth, [], "finished", -1
    reference, free = (None, None) if key is None else (key[1], None)
    previous, before = (None, None) if key is None else key
    inks = None if settings.palette is None else Inks(settings, None if key is None else key[1])
    for position, (index, picture) in enumerate(frames):
        weights = picture if inks is None else inks.densities(picture)
        if not np.any(np.asarray(weights) > 0):
            raise StippleError(
                f"frame {index} is blank (all white): there is nothing to place dots on; leave it out "
                "(--start/--stop/--step) or cut the clip there"
            )
        bandwidth = bandwidth or default_bandwidth(
            settings.n_points, weights.sum(axis=0) if inks is not None else weights
        )
        change = frame_change(before, weights, settings.n_points)
        if previous is not None:
            margin = min(settings.free_margin, CUT_MARGIN) if change > CUT else settings.free_margin
            free, reference = free_dots(previous, reference, weights, replace(settings, free_margin=margin))
        frame = keeper.replay(position, index, weights)
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
    """A periodic Gaussian blur of ``sigma`` pixels of an ``(H, W)`` array or of each of a ``(K, H, W)`` stack."""
    return gaussian_filter(values, (0,) * (np.ndim(values) - 2) + (sigma, sigma), mode="wrap")


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
    the low-frequency correction over all dots (``WARM_LEVELS``)."""
    options = _run_options(settings, stop)
    changed = change > 0
    if not free.any() and not (changed and settings.correct):
        return run(problem, init=previous, iterations=0, correct=False, **options)
    pinned = replace(problem, manifold=PinnedTorus(problem.manifold.scale, free))
    result = run(
        pinned,
        init=previous,
        iterations=(settings.iterations if change > CUT else settings.frame_iterations) if free.any() else 0,
        correct=False,
        **options,
    )
    if result.status == "stopped" or not (changed and settings.correct) or not WARM_LEVELS:
        return result
    result = correct_low_frequencies(problem, result, settings.time_limit, stop, levels=WARM_LEVELS)
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
        # The flat metric, with which the warm frames' pinned phase and correction were measured (docs/video.md);
        # the cold first frame still starts coarse to fine.
        precondition=False,
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


def _defining(settings, identity):
    """The settings a checkpoint must match: the problem's, the warm frames' cap, the start and the identity."""
    init = settings.init if isinstance(settings.init, str) else "points"
    defining = {
        "points": settings.n_points,
        "bandwidth": settings.bandwidth,
        "near_field": bool(settings.near_field),
        "hessian": settings.hessian,
        "seed": settings.seed,
        "init": init,
        "frame_iterations": settings.frame_iterations,
        "change": settings.change,
        "free_margin": settings.free_margin,
    }
    if settings.palette is not None:
        defining.update(
            palette=palette_label(settings.palette), black=settings.black, union_weight=settings.union_weight
        )
    return {**defining, **(identity or {})}


def _result(status, frames, timings, seconds, cold_first=True):
    if frames == 0 and status == "finished":
        raise StippleError("no frame was stippled")
    cold = timings[0] if cold_first and timings and len(timings) == frames else None
    warm = timings[1:] if cold is not None else timings
    average = sum(warm) / len(warm) if warm else None
    message = f"{frames} frames"
    if cold is not None:
        message += f"; frame 0 (cold) {cold:.2f} s"
    if average is not None:
        message += f"; warm-started frames {average:.2f} s each"
    if status == "stopped":
        message = f"stopped after {message}"
    return VideoResult(status, message, frames, len(timings), seconds, cold, average)


class _Keeper:
    """The finished frames' dots for the checkpoint: replayed on resume, saved every so often and at the end."""

    def __init__(self, path, settings, seconds, frames, resume):
        self.path, self.settings, self.seconds, self.every = path, settings, seconds, frames
        self.points, self.indices, self.fingerprints = [], [], []
        self.saved = (time.monotonic(), 0)
        if path is None:
            if resume:
                raise StippleError("resume needs a checkpoint file")
            return
        if not resume and os.path.exists(path):
            raise StippleError(f"{path}: checkpoint exists; resume it or remove it first")
        if resume:
            points, self.indices, self.fingerprints = load_video_checkpoint(path, settings)
            self.points = list(points)
            self.saved = (time.monotonic(), len(self.points))

    @property
    def count(self):
        return len(self.indices)

    def replay(self, position, index, weights):
        """The saved frame at ``position``, checked against the input, or None past the saved frames."""
        if self.path is None or position >= len(self.points):
            return None
        if self.indices[position] != index or self.fingerprints[position] != frame_fingerprint(weights):
            raise StippleError(f"{self.path}: checkpoint is for another input: frame {index} differs")
        return Frame(index, self.points[position], weights, position > 0, True)

    def add(self, frame, weights):
        self.indices.append(frame.index)
        if self.path is None:
            return
        self.points.append(frame.points)
        self.fingerprints.append(frame_fingerprint(weights))
        due_time = self.seconds is not None and time.monotonic() - self.saved[0] >= self.seconds
        due_count = self.every is not None and len(self.points) - self.saved[1] >= self.every
        if due_time or due_count:
            self.save()

    def finish(self, status, seen):
        """Save the finished frames; refuse a finished run that saw fewer frames than the checkpoint holds."""
        if status == "finished" and seen < len(self.points):
            raise StippleError(f"{self.path}: checkpoint holds {len(self.points)} frames, the input only {seen}")
        if self.path is not None and self.points:
            self.save()

    def save(self):
        save_video_checkpoint(self.path, self.points, self.settings, self.indices, self.fingerprints)
        self.saved = (time.monotonic(), len(self.points))
