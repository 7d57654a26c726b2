"""MP4 through PyAV (the ``video`` extra): the encoder that ``stipple video`` streams its frames into, and the
messages of PyAV's errors."""

from fractions import Fraction

import numpy as np

from ..errors import StippleError

NEEDS_PYAV = "needs PyAV: pip install 'stipple[video]'"


def require_av(what):
    """The ``av`` module, or a StippleError saying that ``what`` needs the ``video`` extra."""
    try:
        import av
    except ImportError:
        raise StippleError(f"{what} {NEEDS_PYAV}") from None
    return av


def error_reason(error):
    """The message of an ``OSError`` or a PyAV error: its ``strerror``, else its text, else its type's name."""
    return (getattr(error, "strerror", None) or str(error) or type(error).__name__).strip()


class Mp4Stream:
    """An H.264 MP4 (MPEG-4 Part 2 where PyAV has no libx264) written frame by frame to ``temporary``.

    Pictures are padded by their edge pixels to even sides (the yuv420p encoding needs them).
    """

    def __init__(self, temporary, path, fps):
        self.av = require_av(f"{path}: writing MP4")
        self.temporary, self.path, self.fps = temporary, path, fps
        self.container = self.stream = None

    def write(self, picture):
        rgb = np.asarray(picture.convert("RGB"))
        rgb = np.pad(rgb, ((0, rgb.shape[0] % 2), (0, rgb.shape[1] % 2), (0, 0)), mode="edge")
        try:
            if self.container is None:
                self._open(rgb.shape)
            frame = self.av.VideoFrame.from_ndarray(rgb, format="rgb24")
            self.container.mux(self.stream.encode(frame))
        except (self.av.FFmpegError, OSError) as error:
            raise StippleError(f"{self.path}: cannot write the MP4 ({error_reason(error)})") from None

    def _open(self, shape):
        codec = "libx264" if "libx264" in self.av.codecs_available else "mpeg4"
        self.container = self.av.open(self.temporary, "w", format="mp4")
        self.stream = self.container.add_stream(codec, rate=Fraction(self.fps).limit_denominator(1001))
        self.stream.height, self.stream.width = shape[:2]
        self.stream.pix_fmt = "yuv420p"
        if codec == "libx264":
            self.stream.options = {"crf": "18"}

    def close(self):
        if self.container is None:
            return
        container, self.container = self.container, None
        try:
            try:
                # No stream where opening failed after the container (then there is nothing to flush).
                if self.stream is not None:
                    container.mux(self.stream.encode(None))
            finally:
                container.close()
        except (self.av.FFmpegError, OSError) as error:
            raise StippleError(f"{self.path}: cannot write the MP4 ({error_reason(error)})") from None
