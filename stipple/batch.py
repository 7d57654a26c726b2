"""Batches of images: each stippled exactly as ``stipple torus`` would, written as ``DIR/<stem>.<ext>``, one after
the other here or one task per image on a Dask distributed cluster.

``stipple.pipelines.image.stipple_image`` is the one path from an image to its outputs' bytes; ``run_job`` writes
one image's outputs all-or-nothing (temporary files beside them, then renamed), so that every output file that
exists is whole.
An image is *done* when all its outputs exist and none is older than the image (``is_done``): a rerun of a batch
skips those and redoes the rest, including the image a killed worker was working on.
"""

import glob
import os
import re
import socket
import stat
import threading
import time
import uuid
from dataclasses import dataclass

from .errors import StippleError
from .io.commit import commit_outputs
from .io.safety import check_distinct
from .io.sources import check_regular_file
from .pipelines.image import stipple_image

FORMATS = ("csv", "png", "svg")
# Exit status of a batch in which some images failed: FAILED_BASE + the number failed, at most FAILED_BASE +
# FAILED_CAP (101-125): above 1 (bad data) and 2 (bad usage), below 126-127 (the shell's) and 128 + signal.
FAILED_BASE, FAILED_CAP = 100, 25
# Seconds to wait for a Dask scheduler: a TCP connection (PROBE_TIMEOUT), then the client's whole connection and
# handshake (CONNECT_TIMEOUT).
PROBE_TIMEOUT, CONNECT_TIMEOUT = 2, 10
SCHEDULER_SCHEMES, DEFAULT_SCHEDULER_PORT = ("tcp", "tls"), 8786


@dataclass(frozen=True)
class BatchJob:
    """One image of a batch: its absolute path, its outputs as ``(format, absolute path)`` pairs, what to do to
    it (a ``stipple.pipelines.image.TorusRecipe``), and its name as given (in messages)."""

    image: str
    outputs: tuple
    recipe: object
    name: str = ""


@dataclass
class BatchOutcome:
    """What became of one image: ``status`` "done", "skipped" (its outputs existed) or "failed"; ``message``
    says why it failed or how its run stopped; ``notes``, what its drawing's user must know (dots left out)."""

    image: str
    status: str
    message: str = ""
    seconds: float = 0.0
    iterations: int = 0
    energy: float = float("nan")
    notes: tuple = ()


def parse_formats(text):
    """``"csv,png,svg"`` -> ``(".csv", ".png", ".svg")`` in the order given, each once."""
    names = [part.strip().lower().lstrip(".") for part in str(text).split(",") if part.strip()]
    unknown = [name for name in names if name not in FORMATS]
    if not names or unknown:
        raise StippleError(f"format must be a comma-separated list of {', '.join(FORMATS)}, not {text!r}")
    return tuple(f".{name}" for name in dict.fromkeys(names))


def expand_images(images):
    """The images of a batch: a name with ``*``, ``?`` or ``[`` that is not a file is a glob (as a shell would
    expand it, and as ``stipple video`` takes one), its files in natural order (``2.png`` before ``10.png``)."""
    expanded = []
    for image in images:
        image = str(image)
        if any(char in image for char in "*?[") and not os.path.exists(image):
            files = [name for name in glob.glob(image) if os.path.isfile(name)]
            if not files:
                raise StippleError(f"{image}: no file matches this pattern")
            expanded += sorted(files, key=lambda name: [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", name)])
        else:
            expanded.append(image)
    return expanded


def plan_batch(images, out_dir, formats, recipe):
    """The jobs of a batch, checked before any work.

    Raises
    ------
    StippleError
        If an image is stdin, a directory or not a regular file, two images share a stem (compared ignoring
        case, since they would write the same files on a case-insensitive file system), or an output would
        overwrite an image. The same file given twice (two names, overlapping globs) is one job.
    """
    jobs, stems, seen = [], {}, set()
    for image in images:
        if str(image) == "-":
            raise StippleError("batch reads image files, not stdin ('-')")
        if os.path.isdir(image):
            raise StippleError(f"{image}: is a directory; give its images (e.g. {os.path.join(image, '*.png')})")
        if os.path.exists(image):  # a missing one fails as its job, beside the others
            # A pipe among a shell glob's names waited for a writer, and the whole batch with it (a hostile review).
            check_regular_file(image, "a pipe or a device", "; a batch reads image files")
        if _identity(image) in seen:  # the same file twice (overlapping globs): stippled once
            continue
        seen.add(_identity(image))
        stem = os.path.splitext(os.path.basename(image))[0]
        if stem.casefold() in stems:
            raise StippleError(
                f"{stems[stem.casefold()]} and {image} would both write {os.path.join(out_dir, stem)}.*; "
                "rename one or run them in separate batches"
            )
        stems[stem.casefold()] = image
        outputs = tuple((fmt, os.path.abspath(os.path.join(out_dir, stem + fmt))) for fmt in formats)
        jobs.append(BatchJob(os.path.abspath(image), outputs, recipe, str(image)))
    check_distinct(
        [("image", job.image) for job in jobs], [("output", path) for job in jobs for _, path in job.outputs]
    )
    return jobs


def _identity(path):
    """What makes two names the same file: its device and inode, or for a missing file its real path."""
    try:
        status = os.stat(path)
    except OSError:
        return os.path.realpath(path)
    return (status.st_dev, status.st_ino)


def is_done(job):
    """True if every output of ``job`` is a file and none is older than its image.

    Every output is renamed into place whole (``run_job``), so an existing file is complete; an image whose run
    was cut off (a killed worker, a signal) has none of its outputs, or old ones, and is not done.
    """
    try:
        changed = os.stat(job.image).st_mtime
    except OSError:
        return False
    for _, path in job.outputs:
        try:
            status = os.stat(path)
        except OSError:
            return False
        if not stat.S_ISREG(status.st_mode) or status.st_mtime < changed:
            return False
    return True


def run_job(job):
    """Stipple one image and write its outputs all-or-nothing; every error becomes a failed ``BatchOutcome``.

    Signals and other ``BaseException`` s are not caught: they stop the batch, and the image's temporary files
    are removed on the way out.
    """
    started = time.perf_counter()
    try:
        outputs = stipple_image(job.image, [fmt for fmt, _ in job.outputs], job.recipe)
        commit_outputs([(path, outputs.files[fmt]) for fmt, path in job.outputs])
    except StippleError as error:
        return failed(job, str(error), started)
    except MemoryError:
        return failed(job, "out of memory", started)
    except OSError as error:
        return failed(job, error.strerror or str(error), started)
    except Exception as error:  # a bug must not stop the other images: one line, and the batch goes on
        return failed(job, f"internal error: {type(error).__name__}: {error}", started)
    result = outputs.result
    return BatchOutcome(
        job.name or job.image,
        "done",
        result.message,
        time.perf_counter() - started,
        int(result.iterations),
        float(result.energy),
        tuple(getattr(outputs.files, "warnings", ())),
    )


def failed(job, message, started=None):
    """A failed outcome of ``job``, its message on one line; one that starts by naming the image does not name it
    twice."""
    for name in (job.image, job.name, os.path.basename(job.image)):
        if name and message.startswith(f"{name}: "):
            message = message[len(name) + 2 :]
    seconds = 0.0 if started is None else time.perf_counter() - started
    return BatchOutcome(job.name or job.image, "failed", " ".join(message.split()), seconds)


def run_batch(jobs, on_outcome=None, scheduler=None, force=False):
    """Run every job not done yet (all of them with ``force``), here one after the other or on the Dask
    scheduler at address ``scheduler``, and report each outcome to ``on_outcome(outcome)`` as it comes.

    Returns
    -------
    list of BatchOutcome
        In the order the outcomes came.
    """
    outcomes = []

    def report(outcome):
        outcomes.append(outcome)
        if on_outcome is not None:
            on_outcome(outcome)

    todo = []
    for job in jobs:
        if not force and is_done(job):
            report(BatchOutcome(job.name or job.image, "skipped", "outputs exist"))
        else:
            todo.append(job)
    if scheduler is None:
        for job in todo:
            report(run_job(job))
    elif todo:
        run_on_cluster(todo, scheduler, report)
    return outcomes


def run_on_cluster(jobs, address, report):
    """One Dask task per job on the scheduler at ``address``; each task writes its own outputs.

    The workers must see the images and the output folder at the same paths (a shared file system). A task whose
    worker dies is run again on another worker by the scheduler (up to its ``allowed-failures``); one that still
    fails is reported as failed, and a rerun of the batch redoes it. Each task's result is released as soon as it
    has come, so that a worker dying later does not make the scheduler run its finished tasks again.
    """
    client = connect(address)  # first: it names the missing extra
    from distributed import as_completed

    pending = {}
    try:
        run_id = uuid.uuid4().hex[:8]
        keys = [f"stipple-batch-{run_id}-{index}-{os.path.basename(job.image)}" for index, job in enumerate(jobs)]
        futures = client.map(run_job, jobs, key=keys, pure=False)
        pending = {future.key: (future, job) for future, job in zip(futures, jobs, strict=True)}
        finished = as_completed(futures, loop=client.loop)
        del futures
        for future in finished:
            _, job = pending.pop(future.key)
            try:
                outcome = future.result()
            except Exception as error:  # the task never returned: its worker died too often, or it was lost
                outcome = failed(job, cluster_failure(error))
            future.release()
            report(outcome)
    finally:
        if pending:
            client.cancel([future for future, _ in pending.values()])
        client.close()


def cluster_failure(error):
    """The message of a task that never returned its outcome."""
    if type(error).__name__ == "KilledWorker":
        return "its worker died while running it (Dask KilledWorker: the scheduler's allowed-failures were spent)"
    first = str(error).split(". ")[0]
    return f"task failed on the cluster: {type(error).__name__}: {first}"


def connect(address):
    """A ``distributed.Client`` of the scheduler at ``address``, or a StippleError saying what is missing.

    The address is checked first (``scheduler_address``), then a TCP connection is tried for at most
    ``PROBE_TIMEOUT`` seconds (a refused one is said at once), and the whole connection and handshake are given
    ``CONNECT_TIMEOUT`` seconds: a listener that never answers cannot hang the batch.
    """
    _, host, port = scheduler_address(address)
    Client = cluster_client()  # noqa: N806 (the class, as distributed names it)
    probe(address, host, port)

    def open_client():
        return Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)

    try:
        return bounded(open_client, CONNECT_TIMEOUT + 1, f"cannot reach the Dask scheduler {address}: no answer")
    except StippleError:
        raise
    except (OSError, TimeoutError, ValueError) as error:
        raise StippleError(f"cannot reach the Dask scheduler {address}: {' '.join(str(error).split())}") from None


def cluster_client():
    """``distributed.Client``, or a StippleError naming the extra to install (checked before a batch makes its
    output folder)."""
    try:
        from distributed import Client
    except ImportError:
        raise StippleError(
            "--scheduler needs Dask distributed: pip install 'stipple[cluster]' (or dask[distributed])"
        ) from None
    return Client


def scheduler_address(address):
    """``(scheme, host, port)`` of a scheduler address ``tcp://HOST:PORT`` (or ``HOST:PORT``; ``tls://`` too;
    the port defaults to Dask's 8786), checked: a known scheme, a host, a port in [1, 65535]."""
    text = str(address).strip()
    scheme, separator, rest = text.partition("://")
    if not separator:
        scheme, rest = "tcp", text
    if scheme not in SCHEDULER_SCHEMES:
        raise StippleError(
            f"--scheduler {address!r}: not a Dask scheduler address (tcp://HOST:PORT); {scheme}:// is not supported"
        )
    host, colon, port = rest.rpartition(":")
    if not colon or "]" in port:
        host, port = rest, str(DEFAULT_SCHEDULER_PORT)
    host = host.strip("[]")
    if not host or any(char in host for char in "/ ?#@"):
        raise StippleError(f"--scheduler {address!r}: no host (give tcp://HOST:PORT)")
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise StippleError(f"--scheduler {address!r}: invalid port {port!r} (an integer in [1, 65535])")
    return scheme, host, int(port)


def probe(address, host, port):
    """Raise unless a TCP connection to ``host:port`` opens within ``PROBE_TIMEOUT`` seconds."""

    def attempt():
        try:
            with socket.create_connection((host, port), timeout=PROBE_TIMEOUT):
                return None
        except ConnectionRefusedError:
            return f"connection refused (nothing listens on {host}:{port})"
        except socket.gaierror as error:
            return f"unknown host {host!r} ({error.strerror})"
        except TimeoutError:
            return f"no answer within {PROBE_TIMEOUT} s"
        except OSError as error:
            return error.strerror or str(error)

    problem = bounded(attempt, PROBE_TIMEOUT + 1, f"cannot reach the Dask scheduler {address}: no answer")
    if problem is not None:
        raise StippleError(f"cannot reach the Dask scheduler {address}: {problem}")


def bounded(function, seconds, late):
    """``function()`` run in a daemon thread for at most ``seconds``; a StippleError saying ``late`` after that
    (the thread is left behind: it cannot keep the process alive)."""
    outcome = {}

    def target():
        try:
            outcome["value"] = function()
        except BaseException as error:  # handed back to the caller
            outcome["error"] = error

    thread = threading.Thread(target=target, name="stipple-connect", daemon=True)
    thread.start()
    thread.join(seconds)
    if thread.is_alive():
        raise StippleError(f"{late} within {seconds:g} s")
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


def exit_status(outcomes):
    """0 if no image failed, else ``FAILED_BASE`` + the number failed (at most ``FAILED_BASE + FAILED_CAP``)."""
    count = sum(outcome.status == "failed" for outcome in outcomes)
    return FAILED_BASE + min(count, FAILED_CAP) if count else 0
