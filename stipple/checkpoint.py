"""Checkpoints: the complete CG state in a pickle-free ``.npz``, written atomically.

Format (version 1): arrays ``points``, ``gradient``, ``direction``, ``energies``, ``gradient_norms``;
0-d arrays ``iteration``, ``gradient_curvature``, ``direction_curvature``, ``initial_gradient_norm``;
and ``metadata``, a JSON string with ``format``, ``version``, ``settings`` (what defines the problem),
``fingerprint`` (SHA-256 of the input's coefficients), ``rng_state`` and library ``versions``.
"""

import hashlib
import io
import json
import time
import zipfile
from importlib.metadata import PackageNotFoundError, version

import numpy as np

from .errors import StippleError
from .optimize import CGState
from .outputs import atomic_write

FORMAT = "stipple-checkpoint"
VERSION = 1
ARRAYS = ("points", "gradient", "direction", "energies", "gradient_norms")
SCALARS = ("iteration", "gradient_curvature", "direction_curvature", "initial_gradient_norm")


def fingerprint(problem):
    """SHA-256 of the input as the objective sees it (its exact Fourier coefficients)."""
    return hashlib.sha256(np.ascontiguousarray(problem.discrepancy.target).tobytes()).hexdigest()


def library_versions():
    found = {}
    for name in ("stipple", "numpy", "scipy", "ducc0", "finufft"):
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = "unknown"
    return found


def save_checkpoint(path, state, problem):
    """Write ``state`` of ``problem`` to ``path`` atomically (the previous file stays whole until then)."""
    metadata = {
        "format": FORMAT,
        "version": VERSION,
        "settings": problem.settings,
        "fingerprint": fingerprint(problem),
        "rng_state": state.rng_state,
        "versions": library_versions(),
        "saved": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    buffer = io.BytesIO()
    arrays = {name: np.asarray(getattr(state, name), dtype=np.float64) for name in ARRAYS}
    scalars = {name: np.asarray(getattr(state, name)) for name in SCALARS}
    np.savez(buffer, metadata=np.asarray(json.dumps(metadata)), **arrays, **scalars)
    atomic_write(path, buffer.getvalue())


def load_checkpoint(path, problem):
    """The saved ``CGState`` for ``problem``; refuses files that are damaged, foreign, newer or for another problem."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            contents = {name: archive[name] for name in archive.files}
    except FileNotFoundError:
        raise StippleError(f"{path}: no checkpoint to resume") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        raise StippleError(f"{path}: corrupt or truncated checkpoint ({error})") from None
    metadata = _metadata(path, contents)
    _check_matches(path, metadata, problem)
    state = _state(path, contents, metadata)
    if state.points.shape != (problem.n_points, problem.manifold.dimension):
        raise StippleError(f"{path}: corrupt checkpoint (points have shape {state.points.shape})")
    return state


def _metadata(path, contents):
    if "metadata" not in contents:
        raise StippleError(f"{path}: not a stipple checkpoint")
    try:
        metadata = json.loads(str(contents["metadata"]))
    except (TypeError, ValueError):
        raise StippleError(f"{path}: corrupt checkpoint metadata") from None
    if not isinstance(metadata, dict) or metadata.get("format") != FORMAT:
        raise StippleError(f"{path}: not a stipple checkpoint")
    saved_version = metadata.get("version")
    if not isinstance(saved_version, int) or saved_version > VERSION:
        raise StippleError(
            f"{path}: checkpoint format version {saved_version} is newer than this stipple reads ({VERSION})"
        )
    return metadata


def _check_matches(path, metadata, problem):
    saved = metadata.get("settings", {})
    for key, value in problem.settings.items():
        if saved.get(key) != value:
            raise StippleError(
                f"{path}: checkpoint is for a different problem: {key} was {saved.get(key)!r}, now {value!r}"
            )
    if metadata.get("fingerprint") != fingerprint(problem):
        raise StippleError(f"{path}: checkpoint is for a different problem: the input differs")


def _state(path, contents, metadata):
    missing = [name for name in ARRAYS + SCALARS if name not in contents]
    if missing:
        raise StippleError(f"{path}: corrupt checkpoint (missing {', '.join(missing)})")
    values = {name: contents[name] for name in ARRAYS}
    if not all(np.all(np.isfinite(array)) for array in values.values()):
        raise StippleError(f"{path}: corrupt checkpoint (NaN or infinite values)")
    return CGState(
        points=values["points"],
        gradient=values["gradient"],
        direction=values["direction"],
        gradient_curvature=float(contents["gradient_curvature"]),
        direction_curvature=float(contents["direction_curvature"]),
        iteration=int(contents["iteration"]),
        initial_gradient_norm=float(contents["initial_gradient_norm"]),
        energies=values["energies"].tolist(),
        gradient_norms=values["gradient_norms"].tolist(),
        rng_state=str(metadata.get("rng_state", "")),
    )


class Checkpointer:
    """A CG callback that saves the state every ``seconds`` or every ``iterations`` (whichever is given)."""

    def __init__(self, path, problem, *, seconds=None, iterations=None):
        self.path = path
        self.problem = problem
        self.seconds = seconds
        self.iterations = iterations
        self.last_time = time.monotonic()
        self.last_iteration = None
        self.latest = None

    def __call__(self, state):
        self.latest = state
        if self.last_iteration is None:
            self.last_iteration = state.iteration
        due_by_time = self.seconds is not None and time.monotonic() - self.last_time >= self.seconds
        due_by_count = self.iterations is not None and state.iteration - self.last_iteration >= self.iterations
        if due_by_time or due_by_count:
            self.save(state)
        return False

    def save(self, state=None):
        state = state or self.latest
        if state is None:
            return
        save_checkpoint(self.path, state, self.problem)
        self.last_time = time.monotonic()
        self.last_iteration = state.iteration
