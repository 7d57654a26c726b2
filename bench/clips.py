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


def _photo(name, width, height, offset=0):
    """scikit-image's gray photo ``name`` resized to ``(height, width + offset)`` (float gray in [0, 1])."""
    import skimage.data

    image = Image.fromarray(getattr(skimage.data, name)())
    return np.asarray(image.resize((width + offset, height), Image.Resampling.LANCZOS), float).clip(0, 255) / 255


def disc_clip(frames=16, width=208, height=128):
    """The issue's clip: a horizontal gradient from 65 % darkness at the left to 5 % at the right, a dark disc
    (95 % darkness, radius 15 px) moving 2.5 px per frame to the right along a sine (uint8 gray frames)."""
    y, x = np.mgrid[0:height, 0:width] + 0.5
    base = 1 - (0.65 - 0.6 * x / width)
    clip = []
    for k in range(frames):
        cx = 0.3 * width + 2.5 * k
        cy = 0.5 * height + 0.2 * height * np.sin(2 * np.pi * 2.5 * k / 40)
        cover = np.clip(15 + 0.5 - np.hypot(x - cx, y - cy), 0.0, 1.0)
        clip.append(np.round(255 * (base * (1 - cover) + 0.05 * cover)).astype(np.uint8))
    return clip


def _matched(photo, reference):
    """``photo`` shifted to the mean gray of ``reference``: the frame's total ink stays the same, so that a still
    region keeps its share of the dots (the dots per pixel are M w / sum w)."""
    return np.clip(photo - photo.mean() + reference.mean(), 0.0, 1.0)


def _strip(width, rows):
    """A still caption strip: a horizontal gradient (gray 0.3 to 0.9)."""
    return np.tile(0.3 + 0.6 * (np.arange(width) + 0.5) / width, (rows, 1))


def pan_clip(frames=16, width=208, height=128, speed=2.0):
    """A camera pan: scikit-image's camera photo sliding left ``speed`` px per frame above a still caption strip
    (the bottom quarter)."""
    strip = height // 4
    photo = _photo("camera", width, height - strip, offset=int(np.ceil(speed * frames)))
    clip = []
    for k in range(frames):
        shift = speed * k
        whole, part = int(shift), shift - int(shift)
        view = (1 - part) * photo[:, whole : whole + width] + part * photo[:, whole + 1 : whole + 1 + width]
        clip.append(np.round(255 * np.vstack([view, _strip(width, strip)])).astype(np.uint8))
    return clip


def fade_clip(frames=16, width=208, height=128):
    """A cross-fade from the camera photo to the coins photo (shifted to the same mean gray) above a still caption
    strip."""
    strip = height // 4
    first = _photo("camera", width, height - strip)
    second = _matched(_photo("coins", width, height - strip), first)
    clip = []
    for k in range(frames):
        t = k / max(frames - 1, 1)
        clip.append(np.round(255 * np.vstack([(1 - t) * first + t * second, _strip(width, strip)])).astype(np.uint8))
    return clip


def cut_clip(frames=16, width=208, height=128, at=None):
    """A cut: the camera photo, then from frame ``at`` (default the middle) the moon photo (shifted to the same mean
    gray), above a still strip;
    a dark disc moves across the photos so that the frames between the cuts change too."""
    at = frames // 2 if at is None else at
    strip = height // 4
    first = _photo("camera", width, height - strip)
    photos = first, _matched(_photo("moon", width, height - strip), first)
    y, x = np.mgrid[0 : height - strip, 0:width] + 0.5
    clip = []
    for k in range(frames):
        cover = np.clip(10.5 - np.hypot(x - (0.2 * width + 3 * k), y - 0.4 * height), 0.0, 1.0)
        view = photos[k >= at] * (1 - cover) + 0.05 * cover
        clip.append(np.round(255 * np.vstack([view, _strip(width, strip)])).astype(np.uint8))
    return clip


def zoom_clip(frames=12, width=256, height=160, band=56):
    """A held-out clip (not used to choose any setting): a slow zoom (1.5 % per frame) into scikit-image's
    astronaut photo, beside a still band of dark blocks (15 % and 40 % gray) on the left."""
    import skimage.color
    import skimage.data

    image = Image.fromarray((skimage.color.rgb2gray(skimage.data.astronaut()) * 255).astype(np.uint8))
    y, x = np.mgrid[0:height, 0:band] + 0.5
    still = 0.15 + 0.25 * (np.sin(x / 5.0) * np.cos(y / 7.0) > 0)
    columns, rows = image.size
    clip = []
    for k in range(frames):
        scale = 1 - 0.015 * k
        box = (
            columns * (1 - scale) / 2,
            rows * ((1 - scale) / 2 + 0.05),
            columns * (1 + scale) / 2,
            rows * ((1 + scale) / 2 - 0.25),
        )
        view = np.asarray(image.resize((width - band, height), Image.Resampling.LANCZOS, box=box), float) / 255
        clip.append(np.round(255 * np.hstack([still, view])).astype(np.uint8))
    return clip


def colour_clip(frames=8, width=208, height=128):
    """uint8 RGB frames: scikit-image's coffee photo with a red disc (radius 12 px) moving right 3 px per frame
    across it, above a still strip that runs from cyan to yellow."""
    import skimage.data

    strip = height // 4
    photo = np.asarray(
        Image.fromarray(skimage.data.coffee()).resize((width, height - strip), Image.Resampling.LANCZOS), float
    )
    t = (np.arange(width) + 0.5) / width
    band = np.stack([255 * t, np.full(width, 200.0), 255 * (1 - t)], axis=-1)
    y, x = np.mgrid[0 : height - strip, 0:width] + 0.5
    clip = []
    for k in range(frames):
        cover = np.clip(12.5 - np.hypot(x - (0.25 * width + 3 * k), y - 0.45 * height), 0.0, 1.0)[..., None]
        view = photo * (1 - cover) + np.array([220.0, 30.0, 30.0]) * cover
        clip.append(np.round(np.vstack([view, np.tile(band, (strip, 1, 1))])).clip(0, 255).astype(np.uint8))
    return clip


def through_h264(clip, path):
    """The gray frames of ``clip`` after an H.264 round trip through ``path`` (``write_mp4``; needs PyAV), as the
    issue's clip was given."""
    import av

    write_mp4(clip, path)
    with av.open(str(path)) as container:
        return [frame.to_ndarray(format="gray") for frame in container.decode(video=0)]
