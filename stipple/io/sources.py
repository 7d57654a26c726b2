"""Bounded reads: the bytes of a path, a stream or stdin, never more than ``MAX_INPUT_BYTES``."""

import io
import os
import stat
import sys

from ..errors import StippleError

MAX_INPUT_BYTES = 1 << 30
# The raster formats a drawn picture may come as (``stipple evaluate PICTURE INPUT``): Pillow reads them all.
PICTURE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".gif", ".webp")
# How messages name standard input.
STDIN_NAME = "<stdin>"
# The last standard input read and its bytes: a command may read its input twice (a colour run's inks, then its
# picture's target colour), and a pipe can be read once.
_STDIN = [None, b""]


def check_regular_file(path, reason, advice=""):
    """Raise unless ``path`` is a regular file (links followed; FileNotFoundError where there is none): a device is
    read to its end, a pipe waits for a writer. The message is ``PATH: not a regular file (REASON)ADVICE``."""
    if not stat.S_ISREG(os.stat(path).st_mode):
        raise StippleError(f"{path}: not a regular file ({reason}){advice}")


def stdin_stream():
    """A seekable copy of standard input named ``<stdin>``, read (bounded) once per input stream."""
    if sys.stdin is None:
        raise StippleError("cannot read '-' (stdin): it is closed")
    stream = sys.stdin.buffer
    if _STDIN[0] is not stream:
        _STDIN[:] = [stream, read_source(stream)]
    copy = io.BytesIO(_STDIN[1])
    copy.name = STDIN_NAME
    return copy


def source_or_stdin(source):
    """``source`` as read: a path or stream, or stdin's copy (``stdin_stream``) when it is ``-``."""
    return stdin_stream() if source == "-" else source


# An empty path, most often a shell variable that was not set ("$OUT"): every command's inputs, outputs,
# checkpoint and --init say it in these words.
EMPTY_NAME = "an empty file name (an unset shell variable?)"


def read_source(source, limit=None):
    """Bytes of ``source`` (a path, or a binary file object such as stdin), at most ``limit`` of them
    (default ``MAX_INPUT_BYTES``).

    Raises
    ------
    StippleError
        If the source cannot be read or holds more than ``limit`` bytes (``/dev/zero`` never ends).
    """
    name = str(getattr(source, "name", source))
    limit = MAX_INPUT_BYTES if limit is None else limit
    if name == "":
        raise StippleError(EMPTY_NAME)  # "cannot read : No such file"
    try:
        if hasattr(source, "read"):
            return _read_bounded(source, limit, name)
        with open(source, "rb") as handle:
            return _read_bounded(handle, limit, name)
    except FileNotFoundError as error:
        raise StippleError(missing_file(name, error)) from None
    except OSError as error:
        raise StippleError(f"cannot read {name}: {error.strerror or error}") from None


def missing_file(name, error=None):
    """The message for an input ``name`` that does not exist; ``builtin:NAME`` names a sphere's density (``torus
    builtin:gaussians`` was "No such file or directory": a fifth sweep)."""
    if name.startswith("builtin:"):
        return f"{name}: the built-in densities are the sphere's ('stipple sphere {name}'); give an image file here"
    return f"cannot read {name}: {getattr(error, 'strerror', None) or 'No such file or directory'}"


def _read_bounded(stream, limit, name):
    try:
        status = os.fstat(stream.fileno())
    except (OSError, ValueError, AttributeError):
        status = None
    if status is not None and stat.S_ISREG(status.st_mode) and status.st_size > limit:
        raise StippleError(f"{name}: file is {status.st_size} bytes, more than the {limit} bytes read at most")
    data = stream.read(limit + 1)
    if len(data) > limit:
        raise StippleError(f"{name}: input is longer than the {limit} bytes read at most")
    return data
