"""Videos and frame sequences: frames read from a video file (PyAV) or from a folder or glob of images as densities,
the outputs of a stippled video (a ``frame,x,y`` CSV, MP4 and one PNG or SVG per frame) staged as they come, and
the video checkpoint (pickle-free ``.npz``)."""

import glob
import io
import os
import re
import tempfile
from dataclasses import dataclass
from functools import partial

import numpy as np
from PIL import Image

from ..errors import StippleError
from .commit import StagedOutputs, write_stdout
from .images import check_grid, image_colour, image_density, load_array, load_colour, load_density
from .levels import auto_levels
from .mp4 import Mp4Stream, error_reason, require_av
from .sources import EMPTY_NAME, PICTURE_EXTENSIONS, check_regular_file, missing_file, read_source

# The still formats of a frame sequence (a GIF is read as a video), and .npy maps.
FRAME_EXTENSIONS = tuple(extension for extension in PICTURE_EXTENSIONS if extension != ".gif") + (".npy",)
PATTERN_EXTENSIONS = (".png", ".svg")
# Pillow's decompression-bomb limit, also for frames that PyAV decodes.
MAX_FRAME_PIXELS = int(Image.MAX_IMAGE_PIXELS or 89_478_485)
_FIELD = re.compile(r"%(0?[1-9][0-9]?)?d")


@dataclass
class FrameSource:
    """Frames selected from a video or a sequence of images.

    ``shape`` is the first selected frame's ``(rows, columns)``, ``count`` the number of frames selected when
    known in advance (image sequences, videos whose stream says), ``fps`` the video's frame rate (None for
    images), ``files`` every frame image of a sequence (empty for a video) and ``selection`` the indices taken.
    """

    name: str
    shape: tuple
    count: object
    fps: object
    files: tuple
    selection: range

    def densities(self, *, invert=False, gamma=1.0, levels=None, value_range=None):
        """``(index, w)`` for every selected frame, ``index`` counting the source's frames from 0; ``levels`` as
        for ``load_density``, "auto" the first frame's for every frame (a stretch changing by frame would flicker);
        ``value_range`` the values of ``.npy`` frames sent to 0 and 1, by default the least and the greatest of
        all selected frames (each frame stretched to its own made a fading map look still)."""
        if levels == "auto":
            levels = auto_levels(1 - next(self._frames(lambda load: load(False, 1, None)))[1], "the first frame")
        value_range = self._map_range(value_range)
        yield from self._frames(lambda load: load(invert, gamma, levels, value_range=value_range))

    def _map_range(self, value_range):
        """``value_range`` for the selected ``.npy`` frames, or their values' least and greatest (None if every
        value is the same: each frame then says it is constant)."""
        maps = [
            path for index, path in enumerate(self.files) if index in self.selection and path.lower().endswith(".npy")
        ]
        if value_range is not None and not maps:
            raise StippleError("--range is for .npy frames; a video's or images' gray values are stretched by --levels")
        if value_range is not None or not maps:
            return value_range
        low, high = np.inf, -np.inf
        for path in maps:  # one frame in memory at a time
            values = check_grid(load_array(read_source(path), path), path)
            low, high = min(low, float(values.min())), max(high, float(values.max()))
        return (low, high) if low < high else None

    def colours(self):
        """``(index, rgb)`` for every selected frame: ``(H, W, 3)`` in [0, 1], alpha composited on white."""
        yield from self._frames(lambda load: load(None, None, None, colour=True))

    def _frames(self, read):
        frames = _file_frames(self) if self.files else _video_frames(self)
        found = False
        for index, load in frames:
            density = read(load)
            if density.shape[:2] != self.shape:
                raise StippleError(
                    f"{self.name}: frame {index} is {density.shape[1]}×{density.shape[0]} pixels, but the first is "
                    f"{self.shape[1]}×{self.shape[0]}; every frame must have the same size"
                )
            found = True
            yield index, density
        if not found:
            raise StippleError(f"{self.name}: no frame in the range selected")


def open_frames(source, *, start=0, stop=None, step=1):
    """The frames of ``source``: a video file (MP4, MOV, WebM, GIF, ... through PyAV), a folder of images or a
    glob of them (taken in natural order: ``2.png`` before ``10.png``); frames ``start, start + step, ...`` before
    ``stop``. The first selected frame is decoded at once, so that a bad input fails before any work."""
    if not (isinstance(start, int) and start >= 0 and isinstance(step, int) and step >= 1):
        raise StippleError(f"start must be >= 0 and step >= 1, not {start!r} and {step!r}")
    if stop is not None and stop <= start:
        raise StippleError(f"stop ({stop}) must be larger than start ({start})")
    selection = range(start, stop if stop is not None else 2**62, step)
    source = str(source)
    files = _frame_files(source)
    if files is not None:
        chosen = range(start, min(len(files), selection.stop), step)
        if not chosen:
            raise StippleError(f"{source}: no frame in the range selected ({len(files)} frame images)")
        shape = load_density(files[start]).shape
        _check_size(source, shape)
        return FrameSource(source, shape, len(chosen), None, tuple(files), chosen)
    return _open_video(source, selection)


def _frame_files(source):
    """Frame images of a folder or a glob in natural order; None when ``source`` is a file. A folder's hidden files
    are left out, as the glob leaves them out (a macOS ``._frame1.png`` was read as a frame and stopped the run)."""
    if os.path.isdir(source):
        names = [os.path.join(source, name) for name in os.listdir(source) if not name.startswith(".")]
        files = [
            name for name in names if os.path.splitext(name)[1].lower() in FRAME_EXTENSIONS and os.path.isfile(name)
        ]
    elif any(char in source for char in "*?[") and not os.path.exists(source):
        files = [name for name in glob.glob(source) if os.path.isfile(name)]
    else:
        return None
    if not files:
        raise StippleError(f"{source}: no frames (no image files {', '.join(FRAME_EXTENSIONS)} found)")
    return sorted(files, key=lambda name: [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", name)])


def _file_frames(source):
    """``(index, load)``: ``load(invert, gamma, levels)`` a frame's density, ``load(..., colour=True)`` its RGB."""
    for index in source.selection:
        yield index, partial(_load, source.files[index])


def _load(path, invert, gamma, levels, colour=False, value_range=None):
    if colour:
        return load_colour(path)
    # The range is the .npy frames' (a sequence's images have none); --levels on a map is refused as for a still.
    value_range = value_range if path.lower().endswith(".npy") else None
    return load_density(path, invert=invert, gamma=gamma, levels=levels, value_range=value_range)


def _open_video(source, selection):
    if source == "":
        raise StippleError(EMPTY_NAME)
    if not os.path.exists(source):
        if source.startswith("builtin:"):
            raise StippleError(missing_file(source))
        raise StippleError(f"{source}: no such file, folder or matching frame images")
    if os.path.splitext(source)[1].lower() in FRAME_EXTENSIONS:
        load_density(source)  # an empty or broken file is named as such (it was called "an image" by its name)
        raise StippleError(f"{source}: an image, not a video; use 'stipple torus', or give a folder or glob of frames")
    # A pipe waited for a writer for ever, and could not be read twice (the first frame, then the run).
    check_regular_file(source, "a pipe?", "; a video is read twice: save it to a file first")
    av = require_av(f"{source}: reading a video")
    try:
        with av.open(source) as container:
            if not container.streams.video:
                raise StippleError(f"{source}: not a video (no video stream)")
            stream = container.streams.video[0]
            rate = stream.average_rate or stream.guessed_rate
            total = stream.frames or None
            shape = (stream.height, stream.width)
    except (av.FFmpegError, OSError, ValueError) as error:
        if isinstance(error, StippleError):
            raise
        raise StippleError(f"{source}: not a video PyAV can read ({error_reason(error)})") from None
    _check_size(source, shape)
    _check_gif(source)
    count = None if total is None else len(range(selection.start, min(total, selection.stop), selection.step))
    if count == 0:
        raise StippleError(f"{source}: no frame in the range selected ({total} frames)")
    video = FrameSource(source, shape, count, float(rate) if rate else None, (), selection)
    _, first = next(_video_frames(video, limit=1), (None, None))
    if first is None:
        raise StippleError(
            f"{source}: the video has no frames"
            if selection.start == 0
            else f"{source}: no frame in the range selected"
        )
    video.shape = first(False, 1.0, None).shape
    return video


def _check_gif(source):
    """Refuse a GIF whose frames Pillow cannot all decode: FFmpeg stopped at a broken frame without an error (a
    truncated GIF gave 2 of its 3 frames, exit 0), where ``stipple torus`` refused the same file."""
    with open(source, "rb") as handle:
        if handle.read(4) != b"GIF8":
            return
    try:
        with Image.open(source) as image:
            for index in range(image.n_frames):
                image.seek(index)
                image.load()
    except (OSError, ValueError, EOFError) as error:
        raise StippleError(f"{source}: a broken GIF ({error})") from None


def _video_frames(source, limit=None):
    """``(index, loader)`` of the selected frames of a video, decoded in order."""
    av = require_av(f"{source.name}: reading a video")
    yielded = 0
    try:
        with av.open(source.name) as container:
            for index, frame in enumerate(container.decode(video=0)):
                if index >= source.selection.stop:
                    return
                if index not in source.selection:
                    continue
                _check_size(source.name, (frame.height, frame.width))
                image = Image.fromarray(frame.to_ndarray(format="rgba"), "RGBA")
                yield index, partial(_decoded, image, f"{source.name} frame {index}")
                yielded += 1
                if limit is not None and yielded >= limit:
                    return
    except (av.FFmpegError, OSError) as error:
        raise StippleError(f"{source.name}: cannot decode the video ({error_reason(error)})") from None


def _decoded(image, name, invert, gamma, levels, colour=False, value_range=None):
    """A decoded frame's density, or its colours in [0, 1] alpha composited on white (as ``load_colour``); a
    video has no ``.npy`` frames for ``value_range``."""
    if not colour:
        return image_density(image, invert=invert, gamma=gamma, levels=levels, name=name)
    return image_colour(image, name)


def _check_size(name, shape):
    rows, columns = shape
    if rows < 2 or columns < 2 or rows * columns > MAX_FRAME_PIXELS:
        raise StippleError(
            f"{name}: frames of {columns}×{rows} pixels; they must be at least 2×2 and at most "
            f"{MAX_FRAME_PIXELS} pixels (Pillow's decompression-bomb limit)"
        )


def check_frame_pattern(path):
    """``path`` if it is a frame pattern (one ``%d``, ``%04d``, ...; ``.png`` or ``.svg``), else a StippleError."""
    text = str(path)
    extension = os.path.splitext(text)[1].lower()
    if extension not in PATTERN_EXTENSIONS:
        raise StippleError(f"{text}: frame patterns write {' or '.join(PATTERN_EXTENSIONS)} files")
    bare = text.replace("%%", "")  # '%%' is a literal '%'
    if len(_FIELD.findall(bare)) != 1 or bare.count("%") != 1:
        raise StippleError(
            f"{text}: a video writes one {extension[1:].upper()} per frame: the name needs one %d (or %04d) for "
            "the frame number, e.g. frames/%04d.png"
        )
    if "%" in os.path.dirname(bare):
        # Only the first frame's folder could be checked before the run: a missing one for a later frame failed
        # after every frame was made, and a read-only one was written into by root.
        raise StippleError(f"{text}: the frame number goes in the file name, not in a folder, e.g. frames/%04d.png")
    return text


def frame_path(pattern, index):
    """The file of frame ``index`` for a frame pattern (``frames/%04d.png``, 7 -> ``frames/0007.png``)."""
    number = lambda match: format(index, f"{match.group(1) or ''}d")  # noqa: E731
    return "%".join(_FIELD.sub(number, part) for part in pattern.split("%%"))


def plan_outputs(outputs):
    """Outputs of a video by kind: ``csv`` (paths, ``-`` is stdout), ``mp4`` and ``frames`` (patterns)."""
    plan = {"csv": [], "mp4": [], "frames": []}
    for path in outputs:
        extension = ".csv" if str(path) == "-" else os.path.splitext(str(path))[1].lower()
        if extension in PATTERN_EXTENSIONS:
            plan["frames"].append(check_frame_pattern(path))
        elif extension in (".csv", ".mp4"):
            if _FIELD.search(str(path).replace("%%", "")):  # 'vo/%03d.csv' was written under that very name
                raise StippleError(
                    f"{path}: one {extension[1:].upper()} holds every frame; a %d pattern is for one PNG or SVG "
                    "per frame (e.g. frames/%04d.png)"
                )
            plan[extension[1:]].append(str(path))
        else:
            raise StippleError(
                f"{path}: unknown video output {extension or '(none)'}; use .csv, .mp4, or a .png or .svg frame pattern"
            )
    if plan["mp4"]:
        require_av(f"{plan['mp4'][0]}: writing MP4")
    if plan["csv"].count("-") > 1:
        raise StippleError("'-' (stdout) may be given only once")
    return plan


def check_frames_spare_inputs(patterns, source):
    """Refuse a frame pattern that would overwrite one of the input's frame images (a video has none)."""
    if not source.files:
        return
    inputs = {os.path.realpath(path) for path in source.files}
    for pattern in patterns:
        for index in source.selection:
            if os.path.realpath(frame_path(pattern, index)) in inputs:
                raise StippleError(f"{pattern}: frame {index} would overwrite an input frame; choose another name")


class VideoOutputs:
    """A video's outputs, staged as frames come and renamed all at once by ``commit``.

    ``plan`` is ``plan_outputs``'s; ``draw(points, density, fmt)`` makes one frame's bytes of ``fmt`` (``.png``
    or ``.svg``; ``points`` in unit coordinates of an image of ``shape``, placed from the ``density`` w). The
    CSV (``frame,x,y`` in pixels, row i of every frame is dot i; ``layered``: ``frame,x,y,layer``) and the MP4
    are streamed beside their targets, each frame pattern's files staged one by one; leaving the ``with`` block
    without ``commit`` removes them all.
    """

    def __init__(self, plan, shape, draw, fps, layered=False):
        self.plan, self.shape, self.draw, self.fps, self.layered = plan, shape, draw, fps, layered
        self.staged = StagedOutputs()
        self.tables, self.movies, self.frames = [], [], 0

    def __enter__(self):
        self.staged.__enter__()
        try:
            for path in self.plan["csv"]:
                stream = tempfile.TemporaryFile() if path == "-" else open(self.staged.reserve(path), "wb")
                stream.write(b"frame,x,y,layer\n" if self.layered else b"frame,x,y\n")
                self.tables.append((path, stream))
            self.movies = [Mp4Stream(self.staged.reserve(path), path, self.fps) for path in self.plan["mp4"]]
        except BaseException as error:
            self.__exit__(type(error), error, error.__traceback__)  # what was reserved is removed
            raise
        return self

    def __exit__(self, *exc):
        """Close the streams and remove every file not committed, whatever fails; a stream that cannot be closed
        while the block is already failing (a full disk) does not hide that first error."""
        try:
            self._close()
        except StippleError:
            if exc[0] is None:
                raise
        finally:
            self.staged.__exit__(*exc)

    def add(self, index, points, density, labels=None):
        """Stage frame ``index`` (its number in the source): CSV rows (with the dots' ``labels``), frames, MP4."""
        rows, columns = self.shape
        pixels = points * np.array([columns, rows])
        ends = [f",{label}\n" for label in labels] if self.layered else ["\n"] * len(pixels)
        lines = "".join(f"{index},{x:.6f},{y:.6f}{end}" for (x, y), end in zip(pixels, ends, strict=True)).encode()
        for path, stream in self.tables:
            _write(stream, path, lines)
        drawn = {}
        for pattern in self.plan["frames"]:
            fmt = os.path.splitext(pattern)[1].lower()
            drawn[fmt] = drawn.get(fmt) or self.draw(points, density, fmt)
            self.staged.add(frame_path(pattern, index), drawn[fmt])
        if self.movies:
            picture = Image.open(io.BytesIO(drawn.get(".png") or self.draw(points, density, ".png")))
            for movie in self.movies:
                movie.write(picture)
        self.frames += 1

    def commit(self):
        """Finish the CSV and MP4 files, then rename every output over its target (stdout's CSV written first)."""
        for path, stream in self.tables:
            if path == "-":
                stream.seek(0)
                while chunk := stream.read(1 << 20):
                    write_stdout(chunk)
        self._close()
        self.staged.commit()

    def _close(self):
        """Close every CSV and MP4 stream, then raise the first failure, if any."""
        closers = [partial(_close_table, path, stream) for path, stream in self.tables]
        failures = []
        for close in closers + [movie.close for movie in self.movies]:
            try:
                close()
            except StippleError as error:
                failures.append(error)
        if failures:
            raise failures[0]


def _close_table(path, stream):
    if not stream.closed:
        try:
            stream.close()
        except OSError as error:
            raise StippleError(f"{path}: cannot write ({error.strerror or error})") from None


def _write(stream, path, data):
    try:
        stream.write(data)
    except OSError as error:
        raise StippleError(f"{path}: cannot write ({error.strerror or error})") from None
