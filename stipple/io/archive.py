"""Bounded reads of ``.npz`` archives (checkpoints): each member's stored size is checked against what the reader
expects before any of it is decompressed, and it is read as a plain array, never unpickled."""

import zipfile

from ..errors import StippleError
from .images import load_array
from .sources import check_regular_file

# Room for a member's ``.npy`` header besides its data.
NPY_HEADER_ALLOWANCE = 1 << 12
# The checkpoints' formats, a still's run's (``stipple.checkpoint``) and a video's (``video_checkpoint``): each
# reader names the other's files as such.
STILL_CHECKPOINT, VIDEO_CHECKPOINT = "stipple-checkpoint", "stipple-video-checkpoint"


def open_archive(path):
    """``zipfile.ZipFile(path)``, refused unless ``path`` is a regular file: a zip reader reads a device such as
    /dev/zero to its end (17.6 GB in 40 s before it was killed) and waits on a FIFO for ever. Raises
    FileNotFoundError where there is no file."""
    check_regular_file(path, "a checkpoint is a .npz archive")
    return zipfile.ZipFile(path)


class MemberReader:
    """Reads ``NAME.npy`` members of the open ``zipfile.ZipFile`` ``archive`` of the file ``path``.

    Errors name the file and say ``f"{path}: {foreign} (no member NAME)"`` for a missing member and
    ``f"{path}: {damaged} (...)"`` for one too large or not a plain array.
    """

    def __init__(self, path, archive, foreign="not a stipple checkpoint, or corrupt", damaged="corrupt checkpoint"):
        self.path = path
        self.archive = archive
        self.foreign = foreign
        self.damaged = damaged

    def raw(self, name, limit):
        """The member's bytes; refused without decompressing if it is stored as larger than ``limit``."""
        try:
            info = self.archive.getinfo(f"{name}.npy")
        except KeyError:
            raise StippleError(f"{self.path}: {self.foreign} (no member {name})") from None
        limit += NPY_HEADER_ALLOWANCE
        if info.file_size > limit:
            raise StippleError(
                f"{self.path}: {self.damaged} (member {name} holds {info.file_size} bytes, at most {limit} expected)"
            )
        with self.archive.open(info) as stream:
            return stream.read(limit + 1)

    def value(self, name, limit, kinds):
        """The member as an array of one of the dtype ``kinds`` ("f", "iu", "U"), at most ``limit`` bytes of data."""
        data = self.raw(name, limit)
        try:
            return load_array(data, name, kinds=kinds)
        except StippleError as error:
            raise StippleError(f"{self.path}: {self.damaged} ({error})") from None
