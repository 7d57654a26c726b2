"""Test clips for ``stipple video``: a still gradient with a dark disc moving across one side, and a real clip.

``gradient_clip`` makes 8-bit gray frames: the background is a vertical gradient (gray 0.25 at the top to 0.85 at
the bottom) and a dark disc (gray 0.05, antialiased edge) of radius ``0.1 H`` moves from left to right along the
row at ``0.75 H``, so the picture above and below its path stays still. ``across=True`` moves it across a horizontal
gradient instead, where the image's total ink changes from frame to frame. ``still_mask`` marks the pixels farther
than ``margin`` pixels (periodically, as on the torus) from every pixel that changes during the clip.
"""

from pathlib import Path

import numpy as np
from PIL import Image

REAL_CLIP = "no_time_for_that_tiny.gif"  # scikit-image's 24-frame animated GIF (25×14 pixels)


def gradient_clip(frames=24, width=160, height=120, across=False):
    """``frames`` uint8 gray frames ``(height, width)`` of the moving disc on a still gradient."""
    y, x = np.mgrid[0:height, 0:width] + 0.5
    base = 0.25 + 0.6 * (x / width if across else y / height)
    radius, row = 0.1 * height, 0.75 * height
    clip = []
    for k in range(frames):
        centre = width * (0.125 + 0.75 * k / max(frames - 1, 1))
        cover = np.clip(radius + 0.5 - np.hypot(x - centre, y - row), 0.0, 1.0)
        clip.append(np.round(255 * (base * (1 - cover) + 0.05 * cover)).astype(np.uint8))
    return clip


def still_mask(clip, margin):
    """Pixels farther than ``margin`` pixels from every pixel that changes in ``clip`` (distances wrap around)."""
    from scipy import ndimage

    changed = np.any([frame != clip[0] for frame in clip], axis=0)
    tiled = np.tile(~changed, (3, 3))
    distance = ndimage.distance_transform_edt(tiled)
    rows, columns = changed.shape
    return distance[rows : 2 * rows, columns : 2 * columns] > margin


def write_frames(clip, folder):
    """PNG files ``folder/0000.png``, ... of the frames; returns the folder."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for index, frame in enumerate(clip):
        Image.fromarray(frame).save(folder / f"{index:04d}.png")
    return folder


def write_mp4(clip, path, fps=24):
    """An MP4 of the gray frames (H.264, yuv420p; sides must be even); needs PyAV."""
    import av

    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264" if "libx264" in av.codecs_available else "mpeg4", rate=fps)
        stream.height, stream.width = clip[0].shape
        stream.pix_fmt = "yuv420p"
        for frame in clip:
            container.mux(stream.encode(av.VideoFrame.from_ndarray(np.stack([frame] * 3, axis=-1), format="rgb24")))
        container.mux(stream.encode(None))
    return path


def real_clip(scale=8):
    """scikit-image's animated GIF, each frame scaled up ``scale`` times (nearest neighbour) as uint8 RGB frames,
    or None where scikit-image or PyAV is missing."""
    try:
        import av
        import skimage
    except ImportError:
        return None
    path = Path(skimage.data_dir) / REAL_CLIP
    if not path.exists():
        return None
    with av.open(str(path)) as container:
        frames = [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)]
    return [np.kron(frame, np.ones((scale, scale, 1), dtype=np.uint8)) for frame in frames]
