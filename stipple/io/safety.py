"""Guards around a run's files: outputs never name an input, and one process per checkpoint.

Both work on real files: paths are compared after resolving symlinks, and existing files also by
device and inode (hard links), so ``-o ./link-to-input.png`` is caught as well as ``-o input.png``.
"""

import fcntl
import os

from ..errors import StippleError


def _identity(path):
    """``(device, inode)`` of an existing file (symlinks followed), else None."""
    try:
        status = os.stat(path)
    except (OSError, ValueError):
        return None
    return status.st_dev, status.st_ino


def same_file(first, second):
    """True if the two paths resolve to one file (existing or not; symlinks and hard links included)."""
    if os.path.realpath(first) == os.path.realpath(second):
        return True
    identity = _identity(first)
    return identity is not None and identity == _identity(second)


def check_distinct(inputs, outputs):
    """Refuse outputs that would overwrite an input or each other.

    Parameters
    ----------
    inputs : iterable of (role, path)
        Files the run reads, e.g. ``("image", "in.png")``; ``None``, ``-`` (stdin) and ``builtin:`` names
        are skipped.
    outputs : iterable of (role, path)
        Files the run writes (outputs, checkpoint, reports); ``None`` and ``-`` (stdout) are skipped.

    Raises
    ------
    StippleError
        Naming both roles and the file.
    """
    readable = [(role, str(path)) for role, path in inputs if _is_file_path(path)]
    writable = [(role, str(path)) for role, path in outputs if _is_file_path(path)]
    for index, (role, path) in enumerate(writable):
        for input_role, input_path in readable:
            if same_file(path, input_path):
                raise StippleError(f"{path}: {role} would overwrite the {input_role} {input_path}; choose another name")
        for other_role, other_path in writable[:index]:
            if same_file(path, other_path):
                raise StippleError(f"{path}: given as {other_role} and as {role}; each output needs its own file")


def _is_file_path(path):
    return path is not None and str(path) != "-" and not str(path).startswith("builtin:")


class CheckpointLock:
    """An exclusive lock on a checkpoint for the whole run: ``flock`` on a hidden lock file beside it.

    A second process (or a second lock in this one) is refused at once with a message naming the
    checkpoint. The lock file is removed on release; acquiring re-checks that the locked file is
    still the one at the path, so a release racing with a new lock never leaves two holders.
    """

    def __init__(self, checkpoint):
        self.checkpoint = str(checkpoint)
        directory, name = os.path.split(os.path.realpath(self.checkpoint))  # one lock for every spelling
        self.path = os.path.join(directory, f".{name}.lock")
        self.handle = None

    def acquire(self):
        while self.handle is None:
            try:
                handle = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError as error:
                raise StippleError(f"{self.checkpoint}: cannot lock the checkpoint ({error.strerror})") from None
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                os.close(handle)
                raise StippleError(
                    f"{self.checkpoint}: checkpoint is in use by another stipple run (locked through {self.path})"
                ) from None
            if _identity(self.path) == _identity_of_descriptor(handle):
                self.handle = handle
            else:
                os.close(handle)  # the holder removed it after we opened it; lock the new file instead
        return self

    def release(self):
        if self.handle is None:
            return
        try:
            os.unlink(self.path)
        except OSError:
            pass
        os.close(self.handle)
        self.handle = None

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()


def _identity_of_descriptor(handle):
    status = os.fstat(handle)
    return status.st_dev, status.st_ino
