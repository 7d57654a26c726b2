"""A stippled video's checkpoint while it runs: the finished frames' dots, replayed on resume and saved every so
often and at the end (``stipple.video``; the file format is ``stipple.io.video``'s)."""

import os
import time

from .colour import palette_label
from .errors import StippleError
from .io.video_checkpoint import frame_fingerprint, load_video_checkpoint, save_video_checkpoint


class FrameKeeper:
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
        """The saved dots of the frame at ``position``, checked against the input, or None past the saved
        frames."""
        if self.path is None or position >= len(self.points):
            return None
        if self.indices[position] != index or self.fingerprints[position] != frame_fingerprint(weights):
            raise StippleError(f"{self.path}: checkpoint is for another input: frame {index} differs")
        return self.points[position]

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


# The warm frames' method, in every checkpoint: a checkpoint of another method's frames is refused, not continued
# with frames of another quality (2: every frame in the density-scaled metric, 2026-11-27; older files have none).
WARM_METHOD = 2


def checkpoint_settings(settings, identity):
    """The settings a video's checkpoint must match (``stipple.video.VideoSettings``): the problem's, the warm
    frames' cap and method, the start and ``identity`` (the density's transfer, the frame selection)."""
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
        "warm_method": WARM_METHOD,
    }
    if settings.palette is not None:
        defining.update(
            palette=palette_label(settings.palette), black=settings.black, union_weight=settings.union_weight
        )
    return {**defining, **(identity or {})}
