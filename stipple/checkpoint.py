"""Checkpoints: the complete CG state in a pickle-free ``.npz``, written atomically.

Format (version 1): arrays ``points``, ``gradient``, ``direction``, ``energies``, ``gradient_norms``;
0-d arrays ``iteration``, ``gradient_curvature``, ``direction_curvature``, ``initial_gradient_norm``;
and ``metadata``, a JSON string with ``format``, ``version``, ``settings`` (what defines the problem),
``fingerprint`` (SHA-256 of the input's coefficients), ``rng_state`` and library ``versions``.
"""

import hashlib
import io
import json
import math
import time
import zipfile
from importlib.metadata import PackageNotFoundError, version

import numpy as np

from .checks import MAX_ITERATIONS
from .errors import StippleError
from .io.archive import STILL_CHECKPOINT, VIDEO_CHECKPOINT, MemberReader, open_archive
from .io.commit import atomic_write
from .optimize import CGState

FORMAT = STILL_CHECKPOINT
VERSION = 1
ARRAYS = ("points", "gradient", "direction", "energies", "gradient_norms")
SCALARS = ("iteration", "gradient_curvature", "direction_curvature", "initial_gradient_norm")


def fingerprint(problem):
    """SHA-256 of the input as the objective sees it (its exact Fourier coefficients)."""
    return hashlib.sha256(np.ascontiguousarray(problem.discrepancy.target).tobytes()).hexdigest()


LIBRARIES = ("stipple", "numpy", "scipy", "ducc0", "finufft")


def library_versions(names=LIBRARIES):
    """The installed version of each of ``names`` ("unknown" where one is not installed as a distribution)."""
    found = {}
    for name in names:
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


MAX_METADATA_BYTES = 1 << 20


def load_checkpoint(path, problem):
    """The saved ``CGState`` for ``problem``; refuses files that are damaged, foreign, newer or for another problem.

    Members are read one by one, each only after its stored size has been checked against what the
    problem needs, and every member's dtype, shape and range is validated.
    """
    try:
        with open_archive(path) as archive:
            return _read_checkpoint(path, archive, problem)
    except FileNotFoundError:
        raise StippleError(f"{path}: no checkpoint to resume") from None
    except zipfile.BadZipFile:
        if _starts_like_zip(path):
            raise StippleError(f"{path}: corrupt or truncated checkpoint (a damaged .npz archive)") from None
        raise StippleError(f"{path}: not a stipple checkpoint (not a .npz archive)") from None
    # zipfile raises NotImplementedError for an archive member in a compression method it does not know.
    except (OSError, EOFError, zipfile.LargeZipFile, NotImplementedError, RuntimeError) as error:
        raise StippleError(f"{path}: corrupt or truncated checkpoint ({error})") from None


def _starts_like_zip(path):
    try:
        with open(path, "rb") as stream:
            return stream.read(2) == b"PK"
    except OSError:
        return False


def _read_checkpoint(path, archive, problem):
    reader = _MemberReader(path, archive)
    metadata = _metadata(path, reader.text("metadata", MAX_METADATA_BYTES))
    _check_matches(path, metadata, problem)
    iteration = reader.scalar("iteration", "iu")
    if not 0 <= iteration <= MAX_ITERATIONS:
        raise StippleError(f"{path}: corrupt checkpoint (iteration {iteration} is outside [0, {MAX_ITERATIONS}])")
    shape = (problem.n_points, problem.manifold.dimension)
    points = reader.array("points", shape)
    _check_points(path, points, problem.domain)
    history = {name: reader.array(name, (iteration + 1,)) for name in ("energies", "gradient_norms")}
    curvatures = {name: reader.scalar(name, "f") for name in ("gradient_curvature", "direction_curvature")}
    initial_norm = reader.scalar("initial_gradient_norm", "f")
    if initial_norm < 0 or np.any(history["energies"] < 0) or np.any(history["gradient_norms"] < 0):
        raise StippleError(f"{path}: corrupt checkpoint (negative energies or gradient norms)")
    rng_state = metadata.get("rng_state", "")
    if not isinstance(rng_state, str):
        raise StippleError(f"{path}: corrupt checkpoint metadata (rng_state is not a string)")
    return CGState(
        points=points,
        gradient=reader.array("gradient", shape),
        direction=reader.array("direction", shape),
        iteration=iteration,
        initial_gradient_norm=initial_norm,
        energies=history["energies"].tolist(),
        gradient_norms=history["gradient_norms"].tolist(),
        rng_state=rng_state,
        **curvatures,
    )


class _MemberReader(MemberReader):
    """Checkpoint members as checked values: arrays of a given shape, finite numbers, text."""

    def checked(self, name, limit, shape, kinds):
        array = self.value(name, limit, kinds)
        if array.shape != shape:
            raise StippleError(f"{self.path}: corrupt checkpoint ({name} has shape {array.shape}, not {shape})")
        return array

    def array(self, name, shape):
        """A finite float64 array of exactly ``shape``."""
        array = self.checked(name, 8 * math.prod(shape), shape, "f").astype(np.float64)
        if not np.all(np.isfinite(array)):
            raise StippleError(f"{self.path}: corrupt checkpoint (NaN or infinite values in {name})")
        return array

    def scalar(self, name, kinds):
        """A finite 0-d number of one of the dtype ``kinds`` ("f": float, "iu": integer) as float or int."""
        value = self.checked(name, 16, (), kinds)[()]
        if not np.isfinite(value):
            raise StippleError(f"{self.path}: corrupt checkpoint ({name} is {value})")
        return int(value) if kinds == "iu" else float(value)

    def text(self, name, limit):
        """A 0-d unicode string member."""
        return str(self.checked(name, limit, (), "U")[()])


def _check_points(path, points, domain):
    if domain == "sphere":
        in_range = np.all(np.abs(np.linalg.norm(points, axis=1) - 1) <= 1e-9)
    else:
        in_range = np.all((points >= 0) & (points <= 1))
    if not in_range:
        where = "unit vectors" if domain == "sphere" else "in [0, 1]"
        raise StippleError(f"{path}: corrupt checkpoint (points are not {where})")


def _metadata(path, text):
    try:
        metadata = json.loads(text)
    except (TypeError, ValueError, RecursionError):
        raise StippleError(f"{path}: corrupt checkpoint metadata") from None
    if isinstance(metadata, dict) and metadata.get("format") == VIDEO_CHECKPOINT:
        raise StippleError(f"{path}: checkpoint is of a stipple video run, not of this one")
    if not isinstance(metadata, dict) or metadata.get("format") != FORMAT:
        raise StippleError(f"{path}: not a stipple checkpoint")
    saved_version = metadata.get("version")
    if not isinstance(saved_version, int) or isinstance(saved_version, bool) or saved_version < 1:
        raise StippleError(f"{path}: corrupt checkpoint metadata (format version {saved_version!r})")
    if saved_version > VERSION:
        raise StippleError(
            f"{path}: checkpoint format version {saved_version} is newer than this stipple reads ({VERSION})"
        )
    if not isinstance(metadata.get("settings"), dict) or not isinstance(metadata.get("fingerprint"), str):
        raise StippleError(f"{path}: corrupt checkpoint metadata (settings or fingerprint)")
    # The domain names the command in a message (a list there raised TypeError; a hostile sweep).
    if not isinstance(metadata["settings"].get("domain"), str):
        raise StippleError(f"{path}: corrupt checkpoint metadata (its domain is not a name)")
    return metadata


def _check_matches(path, metadata, problem):
    saved, current = _as_given(metadata["settings"]), _as_given(problem.settings)
    # Over both sides' keys: a colour run's classes and a progressive run's order are missing from the other's.
    differ = [key for key in {**saved, **current} if saved.get(key) != current.get(key)]
    if "domain" in differ:
        raise StippleError(
            f"{path}: checkpoint is of a {COMMANDS.get(saved.get('domain'), 'another')} run, not of this one"
        )
    if differ:
        # The option that was changed, before the settings it changes with it (-N follows -M and --length).
        differ.sort(key=_naming_order)
        what = SETTING_NAMES.get(differ[0], differ[0])
        if differ[0] in ("points", "shape") or (differ[0] == "length" and saved.get("domain") == "line"):
            # A line's length, nodes and padded image follow both the image and --length (its -M is "vertices").
            what = {"sphere": "the map, -M or a design's -t", "line": "the image or --length"}.get(
                saved.get("domain"), "the image or -M"
            )
        details = "; ".join(f"{key} was {_short(saved.get(key))}, now {current.get(key)!r}" for key in differ[:2])
        raise StippleError(
            f"{path}: checkpoint is for a different run: {what} differs ({details}); "
            "resume with the same image and options"
        )
    if metadata["fingerprint"] != fingerprint(problem):
        raise StippleError(
            f"{path}: checkpoint is for a different run: the input differs (the image, or --invert, --gamma, --levels)"
        )


# What a checkpoint's other settings are on the command line, and the order in which a change is named: the
# options first, the settings they change after them (FIRST_NAMED, then any other, then LAST_NAMED).
SETTING_NAMES = {
    "bandwidth": "-N (the bandwidth; without -N it follows the image, its --invert, --gamma or --levels, and -M)",
    "vertices": "-M (the line's vertices)",
    "separation": "--palette",
    "black": "--black",
    "classes": "--palette or --black (the inks)",
    "class_points": "-M, --palette or --black (the inks' dots)",
    "class_bandwidths": "-N (the inks' bandwidths)",
    "class_fingerprint": "the image (the inks' densities)",
    "term_weights": "--union-weight",
    "order": "--order progressive",
    "kernel": "--kernel",
    "near_field": "--near-field / --no-near-field",
    "hessian": "--hessian",
    # A line's own settings, which follow the options (named before them).
    "subdivisions": "the line's nodes (they follow -M and --length)",
    "margin": "the line's blank margin (it follows --length)",
    "exclude": "the line's near field (it follows -N and --length)",
}
FIRST_NAMED = [
    "separation",
    "black",
    "classes",
    "order",
    "vertices",
    "length",
    "points",
    "shape",
    "kernel",
    "near_field",
]
LAST_NAMED = [
    "term_weights",
    "class_points",
    "metric",
    "class_bandwidths",
    "bandwidth",
    "class_fingerprint",
    "subdivisions",
    "margin",
    "exclude",
]


def _as_given(settings):
    """``settings`` with a line's vertices, its nodes over their subdivisions: the -M a message names (a changed
    --length was reported as "points was 900, now 300", its nodes, which read as -M: a fifth sweep)."""
    nodes, subdivisions = settings.get("points"), settings.get("subdivisions")
    if settings.get("domain") != "line" or not isinstance(nodes, int) or not isinstance(subdivisions, int):
        return settings
    return {"vertices": nodes // max(subdivisions, 1), **settings}


def _naming_order(key):
    if key in FIRST_NAMED:
        return FIRST_NAMED.index(key)
    return len(FIRST_NAMED) + (1 + LAST_NAMED.index(key) if key in LAST_NAMED else 0)


COMMANDS = {"torus": "stipple torus or colour", "sphere": "stipple sphere or design", "line": "stipple line"}


def _short(value, limit=60):
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


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


def saved_settings(path):
    """The ``settings`` a checkpoint was saved with (to rebuild the problem it was written for), or ``{}`` where
    the file cannot be read as a checkpoint (``load_checkpoint`` then says why)."""
    try:
        with open_archive(path) as archive:
            return _metadata(path, _MemberReader(path, archive).text("metadata", MAX_METADATA_BYTES))["settings"]
    except (StippleError, OSError, EOFError, zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError):
        return {}
