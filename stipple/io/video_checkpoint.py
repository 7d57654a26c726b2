"""A video's checkpoint: the finished frames' points with their source indices and density fingerprints, in a
pickle-free ``.npz`` (``stipple.video_keeper`` keeps it during a run)."""

import hashlib
import io
import json
import zipfile

import numpy as np

from ..errors import StippleError
from .archive import STILL_CHECKPOINT, VIDEO_CHECKPOINT, MemberReader, open_archive
from .commit import atomic_write
from .mp4 import error_reason


def frame_fingerprint(density):
    """SHA-256 of a frame's density (what a checkpoint compares on resume)."""
    return hashlib.sha256(np.ascontiguousarray(density, dtype=np.float64).tobytes()).hexdigest()


CHECKPOINT_FORMAT = VIDEO_CHECKPOINT
CHECKPOINT_VERSION = 1
MAX_METADATA_BYTES = 1 << 24


def save_video_checkpoint(path, points, settings, indices, fingerprints):
    """Write the finished frames (``points`` of shape ``(K, M, 2)``, their source ``indices`` and density
    ``fingerprints``) and the run's ``settings`` to ``path`` atomically, as a pickle-free ``.npz``."""
    metadata = {
        "format": CHECKPOINT_FORMAT,
        "version": CHECKPOINT_VERSION,
        "settings": settings,
        "indices": [int(index) for index in indices],
        "fingerprints": list(fingerprints),
    }
    buffer = io.BytesIO()
    np.savez(buffer, metadata=np.asarray(json.dumps(metadata)), points=np.asarray(points, dtype=np.float64))
    atomic_write(path, buffer.getvalue())


def load_video_checkpoint(path, settings):
    """``(points, indices, fingerprints)`` of a video checkpoint for a run with ``settings``; refuses files that are
    damaged, foreign, or for other settings. Nothing is unpickled and every member's size is checked first."""
    try:
        with open_archive(path) as archive:
            reader = MemberReader(path, archive, "not a video checkpoint", "damaged video checkpoint")
            metadata = _checkpoint_metadata(path, reader.value("metadata", MAX_METADATA_BYTES, "U"))
            for key, value in settings.items():
                if metadata["settings"].get(key) != value:
                    raise StippleError(
                        f"{path}: checkpoint is for another run: {key} was "
                        f"{metadata['settings'].get(key)!r}, now {value!r}"
                    )
            frames, count = len(metadata["indices"]), settings["points"]
            points = reader.value("points", 16 * frames * count, "f").astype(np.float64)
    except FileNotFoundError:
        raise StippleError(f"{path}: no checkpoint to resume") from None
    except (zipfile.BadZipFile, OSError, EOFError, NotImplementedError, RuntimeError) as error:
        raise StippleError(f"{path}: not a video checkpoint, or damaged ({error_reason(error)})") from None
    if points.shape != (frames, count, 2) or not np.all((points >= 0) & (points <= 1)):
        raise StippleError(f"{path}: damaged video checkpoint (points of shape {points.shape} or outside [0, 1])")
    return points, metadata["indices"], metadata["fingerprints"]


def _checkpoint_metadata(path, text):
    try:
        metadata = json.loads(str(text[()]))
    except (TypeError, ValueError, RecursionError):
        raise StippleError(f"{path}: damaged video checkpoint metadata") from None
    if isinstance(metadata, dict) and metadata.get("format") == STILL_CHECKPOINT:
        raise StippleError(f"{path}: checkpoint is of a still's run (stipple torus, sphere, colour, line or design)")
    if not isinstance(metadata, dict) or metadata.get("format") != CHECKPOINT_FORMAT:
        raise StippleError(f"{path}: not a video checkpoint")
    if metadata.get("version") != CHECKPOINT_VERSION:
        raise StippleError(f"{path}: video checkpoint version {metadata.get('version')!r} is not {CHECKPOINT_VERSION}")
    indices, prints = metadata.get("indices"), metadata.get("fingerprints")
    valid = isinstance(metadata.get("settings"), dict) and isinstance(indices, list) and isinstance(prints, list)
    if not valid or len(indices) != len(prints) or not all(isinstance(i, int) for i in indices):
        raise StippleError(f"{path}: damaged video checkpoint metadata")
    return metadata
