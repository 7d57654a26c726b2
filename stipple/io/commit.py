"""The all-or-nothing commit of output files: every temporary file written and fsynced, then all renamed; and the
checks made on output paths before a long run."""

import contextlib
import errno
import os
import shutil
import signal
import stat
import sys
import tempfile

from ..errors import StippleError

FORMATS = (".csv", ".svg", ".png", ".geojson", ".json")
# The formats of points on a flat image (the torus, colour and the line): GeoJSON is for sphere points.
FLAT_FORMATS = (".csv", ".svg", ".png")


def output_format(path, allowed=FORMATS):
    """The format of ``path`` by its extension (``-`` is CSV on stdout), one of ``allowed``."""
    if str(path) == "-":
        return ".csv"
    extension = os.path.splitext(str(path))[1].lower()
    if extension not in allowed and os.path.isdir(path):  # "unknown output format (none)" for a folder
        example = os.path.join(path, "dots" + allowed[0])
        raise StippleError(f"{path}: is a directory; name a file in it, such as {example}")
    if extension not in allowed:
        what = "GeoJSON output is for sphere points" if extension in FORMATS else "unknown output format"
        found = "" if extension in FORMATS else f" {extension or '(none)'}"
        raise StippleError(f"{path}: {what}{found}; use one of {', '.join(allowed)}")
    return extension


def check_writable(path):
    """Raise if the directory of ``path`` cannot take a new file (checked before a long run)."""
    if str(path) == "-":
        if sys.stdout is None:
            raise StippleError("cannot write to stdout: it is closed")
        return
    path = through_links(path)
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        if os.path.exists(directory):
            raise StippleError(f"{path}: {directory} is a file, not a directory")
        raise StippleError(f"{path}: directory {directory} does not exist")
    if os.path.isdir(path):
        raise StippleError(f"{path}: is a directory")
    _check_regular(path)
    _check_name_length(path, directory)
    if read_only(directory):
        raise StippleError(f"{path}: not writable (the folder {directory} is read-only)")
    if os.path.exists(path) and read_only(path):
        raise StippleError(f"{path}: is read-only; make it writable or choose another name")
    try:
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError as error:
        raise StippleError(f"{path}: not writable ({error.strerror})") from None


def read_only(path):
    """Whether ``path`` is read-only by its mode: refused as an output or output folder even for root, who could
    write it."""
    return not os.stat(path).st_mode & 0o222


def _check_name_length(path, directory):
    """Raise where the file name of ``path`` is longer than its folder's file system allows (a 300-byte name was
    refused only by the rename at the end, after the whole run)."""
    name = os.fsencode(os.path.basename(path))
    try:
        longest = os.pathconf(directory, "PC_NAME_MAX")
    except (OSError, ValueError):
        longest = 255
    if len(name) > longest:
        raise StippleError(f"{str(path)[:40]}...: the file name is {len(name)} bytes, more than the {longest} allowed")


def through_links(path):
    """``path``, or the file its symbolic link names (followed to the end, even where that file does not exist
    yet): outputs and checkpoints are written through a link to its file. Renamed over the link, a resumed
    checkpoint's link became a file of its own, and its file kept the old state for the next resume. A loop of
    links is refused (it was replaced by a file: a hostile sweep)."""
    if not os.path.islink(path):
        return path
    try:
        os.stat(path)
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise StippleError(f"{path}: a loop of symbolic links (they never reach a file)") from None
    return os.path.realpath(path)


def make_folder(directory):
    """Make the output folder ``directory`` (and its missing parents) unless it exists, then ``check_folder`` it.
    A missing folder is refused where the nearest existing one above it is read-only by its mode, as
    ``check_writable`` refuses a file there, even for root (who could write into it: a hostile sweep)."""
    if os.path.islink(directory) and not os.path.exists(directory):  # "cannot make ... (File exists)": a sweep
        raise StippleError(f"{directory}: a symbolic link to no folder (dangling, or a loop of links)")
    if not os.path.isdir(directory):
        above = os.path.dirname(os.path.abspath(directory))
        while not os.path.exists(above):
            above = os.path.dirname(above)
        if os.path.isdir(above) and read_only(above):
            raise StippleError(f"{directory}: cannot make the output folder (the folder {above} is read-only)")
        try:
            os.makedirs(directory, exist_ok=True)
        except OSError as error:
            raise StippleError(f"{directory}: cannot make the output folder ({error.strerror or error})") from None
    check_folder(directory)


def check_folder(directory):
    """Raise, naming ``directory``, unless it is a folder that can take new files."""
    if not os.path.isdir(directory):
        raise StippleError(f"{directory}: is not a folder")
    if read_only(directory):
        raise StippleError(f"{directory}: the output folder is read-only; make it writable or choose another")
    try:
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError as error:
        raise StippleError(f"{directory}: the output folder is not writable ({error.strerror})") from None


def atomic_write(path, data):
    """Write ``data`` (bytes) to ``path`` so that readers see the old file or the whole new one."""
    commit_outputs([(path, data)])


def commit_outputs(items):
    """Write every ``(path, bytes)`` of ``items`` all-or-nothing (``-`` is stdout).

    Each file is first written to a temporary file beside it (flushed and fsynced); only when all of
    them are written (and stdout has taken its share) are they renamed over their targets, with
    ``STOP_SIGNALS`` held back during the renames. Any failure or signal before that removes every temporary
    file and leaves every existing output as it was.
    """
    with StagedOutputs() as staged:
        for path, data in items:
            staged.add(path, data)
        staged.commit()


class StagedOutputs:
    """Outputs written to temporary files as they come and renamed over their targets all at once.

    ``add`` writes one file's temporary (fsynced) beside its target at once, so that a long run (the frames of
    a video) need not hold every file in memory; ``-`` (stdout) is kept until ``commit``. ``commit`` writes
    stdout, then renames every temporary with ``STOP_SIGNALS`` held back. Leaving the ``with`` block without
    a commit (an error, a signal) removes every temporary file and leaves every existing output as it was.
    """

    def __init__(self):
        self._temporaries = []
        self._stdout = []
        self._reserved = set()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.discard()

    def add(self, path, data):
        """Stage ``data`` (bytes) for ``path``."""
        if str(path) == "-":
            self._stdout.append(data)
        else:
            path = through_links(path)
            self._temporaries.append((_write_temporary(path, data), path))

    def reserve(self, path):
        """An empty temporary file beside ``path`` for the caller to write (a large file streamed as it grows,
        such as a video), renamed over ``path`` at ``commit`` (and fsynced first) or removed with the others."""
        path = through_links(path)
        temporary = _write_temporary(path, b"")
        self._temporaries.append((temporary, path))
        self._reserved.add(temporary)
        return temporary

    def commit(self):
        """Write stdout's share, then rename every staged file over its target: all of them, or (a rename refused)
        none of the files, every target replaced so far put back as it was (stdout's share is written by then)."""
        for temporary, path in self._temporaries:
            if temporary in self._reserved:
                _fsync(temporary, path)
        for _, path in self._temporaries:
            _check_not_folder(path)
        for data in self._stdout:
            write_stdout(data)
        self._stdout = []
        with _signals_held():
            _replace_all(self._temporaries)
        self._temporaries = []

    def discard(self):
        """Remove every temporary file not yet renamed."""
        for temporary, _ in self._temporaries:
            _remove(temporary)
        self._temporaries = []


def _replace_all(pairs):
    """``os.replace`` every ``(temporary, path)`` of ``pairs``, all or none.

    Each existing target is first kept under a second name beside it (a hard link, so the target itself never
    goes missing: a reader or a crash sees the old file or the new one). If a rename fails, every target replaced
    so far gets its old file back (or is removed where there was none) and the error names the output; a target
    that cannot be put back keeps its old file under the second name, which the error names too. The second names
    are removed once every rename is done.
    """
    replaced = []
    try:
        for temporary, path in pairs:
            replaced.append((path, _keep_previous(path)))
            os.replace(temporary, path)
    except OSError as error:
        # A new output's name that cannot be removed has no old file to keep (its previous is None).
        kept = [previous for done, previous in reversed(replaced) if not _put_back(done, previous) and previous]
        also = f"; the old file is kept as {', '.join(kept)}" if kept else ""
        raise StippleError(f"{path}: cannot write ({error.strerror or error}){also}") from None
    for _, previous in replaced:
        if previous is not None:
            with contextlib.suppress(OSError):
                _remove(previous)


def _keep_previous(path):
    """A second name beside the existing file ``path`` for it (a hard link, or a copy where the file system has
    none), or None where there is no file."""
    if not os.path.lexists(path):
        return None
    handle, previous = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)), prefix=".stipple-", suffix=".old")
    os.close(handle)
    os.unlink(previous)
    try:
        os.link(path, previous, follow_symlinks=False)
    except OSError:
        shutil.copy2(path, previous, follow_symlinks=False)
    return previous


def _put_back(path, previous):
    """Undo one rename of ``_replace_all``: the old file back at ``path``, or no file where none was; False where
    that fails (the old file then stays at ``previous``)."""
    try:
        if previous is None:
            _remove(path)
        elif _same_file(previous, path):  # never replaced (a rename over a hard link of itself would do nothing)
            os.unlink(previous)
        else:
            os.replace(previous, path)
    except OSError:
        return False
    return True


def _same_file(first, second):
    """Whether two names are links to one file (the links themselves, not what a symbolic link points to)."""
    try:
        one, other = os.lstat(first), os.lstat(second)
    except FileNotFoundError:
        return False
    return (one.st_dev, one.st_ino) == (other.st_dev, other.st_ino)


def _check_not_folder(path):
    """Refuse an output whose place is taken by a folder, or by anything else but a file (``_check_regular``)."""
    if os.path.isdir(path):
        raise StippleError(f"{path}: cannot write (it is a folder)")
    _check_regular(path)


# What an output's place may hold besides a file, by ``stat``'s test: renamed over, each became a file.
_NOT_FILES = (
    ("a named pipe", stat.S_ISFIFO),
    ("a device", stat.S_ISCHR),
    ("a device", stat.S_ISBLK),
    ("a socket", stat.S_ISSOCK),
)


def _check_regular(path):
    """Refuse an output whose place is taken by a named pipe, a device or a socket (or a link to one): the finished
    file renamed over it replaced it, so a reader of the pipe got nothing and a device node became a file."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return
    for kind, test in _NOT_FILES:
        if test(mode):
            raise StippleError(f"{path}: cannot write (it is {kind}, not a regular file)")


def _write_temporary(path, data):
    """A fsynced temporary file in the directory of ``path`` holding ``data``, with the mode ``path`` will get."""
    _check_not_folder(path)
    directory = os.path.dirname(os.path.abspath(path))
    try:
        handle, temporary = tempfile.mkstemp(dir=directory, prefix=".stipple-", suffix=".tmp")
    except OSError as error:
        raise StippleError(f"{path}: cannot write ({error.strerror})") from None
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        mode = os.stat(path).st_mode & 0o777 if os.path.exists(path) else 0o666 & ~_umask()
        os.chmod(temporary, mode)
    except BaseException as error:
        _remove(temporary)
        if isinstance(error, OSError):
            raise StippleError(f"{path}: cannot write ({error.strerror or error})") from None
        raise
    return temporary


def _fsync(temporary, path):
    try:
        with open(temporary, "rb") as stream:
            os.fsync(stream.fileno())
    except OSError as error:
        raise StippleError(f"{path}: cannot write ({error.strerror or error})") from None


def _remove(path):
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass


# The signals that end a command cleanly (temporaries removed, locks released): Ctrl-C, kill, and a closed terminal
# or dropped SSH session (SIGHUP left eight temporaries and a lock: a hostile review). Not on Windows, which has no
# SIGHUP.
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


def taken_signals():
    """The ``STOP_SIGNALS`` a command takes over: those its caller has not set to be ignored (``nohup``'s SIGHUP,
    a script's background job's SIGINT stay ignored)."""
    return [number for number in STOP_SIGNALS if signal.getsignal(number) is not signal.SIG_IGN]


@contextlib.contextmanager
def _signals_held():
    """``taken_signals`` received in the block are delivered after it (main thread only; else a no-op).

    The Python-level handlers are swapped for a recorder, which works whichever thread the kernel
    picks for the signal; recorded signals are raised again once the previous handlers are back.
    """
    caught = []
    previous = {}
    try:
        for number in taken_signals():
            previous[number] = signal.signal(number, lambda number, frame: caught.append(number))
    except ValueError:  # not the main thread: signals cannot be handled here anyway
        pass
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, signal.SIG_DFL if handler is None else handler)
        for number in dict.fromkeys(caught):
            signal.raise_signal(number)


def write_stdout(data):
    """Write ``data`` (bytes) to stdout; a closed or full stdout is a StippleError, not a traceback."""
    stream = sys.stdout
    if stream is None:
        raise StippleError("cannot write to stdout: it is closed")
    try:
        stream.flush()
        # A pipe whose reader stops part-way takes a short write without an error (the next write has it): a
        # video's CSV to `| dd count=20` exited 0 with a fifth of it written (a hostile sweep).
        remaining = memoryview(data)
        while remaining:
            written = stream.buffer.write(remaining)
            if not written:
                raise OSError("the write was not taken")
            remaining = remaining[written:]
        stream.buffer.flush()
    except (OSError, ValueError) as error:
        _discard_stdout()
        raise StippleError(f"cannot write to stdout ({getattr(error, 'strerror', None) or error})") from None


def _discard_stdout():
    """Point stdout at /dev/null so that the interpreter's final flush cannot fail a second time."""
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)
    except (OSError, ValueError, AttributeError):
        pass


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask
