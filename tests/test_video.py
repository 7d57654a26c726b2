"""Stippled video (``stipple.video``, ``stipple video``): coherent dots, checkpoints, outputs and bad inputs."""

import io
import resource

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image
from safety_helpers import leftovers, stipple_process
from scipy.ndimage import gaussian_filter

from stipple import StippleError
from stipple.cli import main
from stipple.measures.evaluate import discrepancy_energy, exact_blurs, psnr
from stipple.torus import halftone_torus, torus_problem
from stipple.video import CUT, VideoSettings, frame_change, free_dots, stipple_video

COUNT, BANDWIDTH = 400, 48


def moving_disc(frames=6, width=64, height=48):
    """Gray frames in [0, 1]: a still vertical gradient, a dark disc moving right along its lower quarter."""
    y, x = np.mgrid[0:height, 0:width] + 0.5
    clip = []
    for k in range(frames):
        cover = np.clip(0.1 * height + 0.5 - np.hypot(x - width * (0.2 + 0.1 * k), y - 0.75 * height), 0, 1)
        clip.append((0.25 + 0.6 * y / height) * (1 - cover) + 0.05 * cover)
    return clip


def stippled(clip, **options):
    frames = []
    settings = VideoSettings(n_points=COUNT, bandwidth=BANDWIDTH, threads=1, **options.pop("settings", {}))
    result = stipple_video(enumerate(1 - g for g in clip), settings, on_frame=frames.append, **options)
    return result, frames


def test_still_dots_stay_and_every_frame_is_as_good_as_a_cold_run():
    clip = moving_disc()
    result, frames = stippled(clip)
    assert result.status == "finished" and [f.index for f in frames] == list(range(len(clip)))
    rows, columns = clip[0].shape
    spacing = np.sqrt(2 / (np.sqrt(3) * COUNT / (rows * columns)))  # pixels, at the mean density
    still = lambda points: points[:, 1] * rows < 0.45 * rows  # noqa: E731 (far above the disc's path)
    for before, after in zip(frames, frames[1:], strict=False):
        chosen = still(before.points)
        moves = np.hypot(*((after.points - before.points)[chosen] * [columns, rows]).T) / spacing
        assert np.median(moves) < 0.05 and np.percentile(moves, 95) < 0.2
    for frame, gray in zip(frames, clip, strict=True):
        problem = torus_problem(1 - gray, COUNT, BANDWIDTH, threads=1, near_field=False)
        cold = halftone_torus(1 - gray, COUNT, BANDWIDTH, threads=1, seed=0).points
        assert discrepancy_energy(problem, frame.points) < 1.5 * discrepancy_energy(problem, cold)


def disc_on_a_gradient(k, width=96, height=64, radius=8.0, step=2.0):
    """Issue 35's clip, smaller: darkness from 0.65 at the left to 0.05 at the right, a disc of darkness 0.95
    moving ``step`` px per frame to the right; returns frame ``k``'s darkness and the disc's centre."""
    y, x = np.mgrid[0:height, 0:width] + 0.5
    centre = (0.3 * width + step * k, 0.5 * height)
    cover = np.clip(radius + 0.5 - np.hypot(x - centre[0], y - centre[1]), 0, 1)
    return (0.65 - 0.6 * x / width) * (1 - cover) + 0.95 * cover, centre


def test_no_light_halo_ahead_of_a_moving_disc():
    # Before the low-frequency correction of warm frames, the disc took its ink from the dots just ahead of it
    # (only those near a change could move): after 10 frames the blurred dots ahead were 0.0062 lighter than the
    # image and the frame's worst local error 4.8 times a cold run's (0.0129 against 0.0027).
    count, bandwidth, frames, radius = 600, 64, 10, 8.0
    done = []
    settings = VideoSettings(n_points=count, bandwidth=bandwidth, threads=1)
    stipple_video(((k, disc_on_a_gradient(k)[0]) for k in range(frames)), settings, on_frame=done.append)
    weights, (cx, cy) = disc_on_a_gradient(frames - 1)
    y, x = np.mgrid[0 : weights.shape[0], 0 : weights.shape[1]] + 0.5
    ahead = (x > cx + radius) & (x < cx + radius + 12) & (np.abs(y - cy) < radius)
    image, dots = exact_blurs(weights, done[-1].points, 4.0)
    # The cold runs' own worst local errors scatter by half between seeds at this size (0.0025-0.0037 over four
    # seeds): the frame is held to the median of three.
    cold_worst = []
    for seed in range(3):
        cold = halftone_torus(weights, count, bandwidth, threads=1, seed=seed).points
        cold_worst.append(np.abs(np.subtract(*exact_blurs(weights, cold, 4.0))).max())
    cold_worst = float(np.median(cold_worst))
    assert (image - dots)[ahead].max() < 1.3 * cold_worst
    assert np.abs(image - dots).max() < 1.3 * cold_worst


def camera_to_coins(size, steps):
    """Darkness of a cross-fade from the camera photo to the coins photo (shifted to its mean gray) at ``steps``."""
    from skimage import data, transform

    first = transform.resize(data.camera() / 255.0, size, anti_aliasing=True)
    second = transform.resize(data.coins() / 255.0, size, anti_aliasing=True)
    second += first.mean() - second.mean()
    return [np.clip(1 - ((1 - t) * first + t * second), 0.02, 1) for t in steps]


def test_a_cross_fade_is_as_good_as_cold_runs_where_a_viewer_looks():
    # Every photo pixel changes every frame. With the correction of plain E_N levels only (N / 3 and N / 6, before
    # the smooth deformation) the frames fell 3.5-7.7 dB (mean 5.7) below their cold runs at sigma 4 px: those
    # levels could not fix the middle frequencies (12-24 cycles per frame) that the blur still sees.
    count, clip = 600, camera_to_coins((64, 96), np.linspace(0, 1, 6))
    done = []
    stipple_video(enumerate(clip), VideoSettings(n_points=count, threads=1), on_frame=done.append)
    below = []
    for weights, frame in zip(clip[1:], done[1:], strict=True):
        cold = halftone_torus(weights, count, threads=1).points
        below.append(psnr(*exact_blurs(weights, cold, 4.0)) - psnr(*exact_blurs(weights, frame.points, 4.0)))
    assert np.mean(below) < 3 and max(below) < 5


def last_frames_below_stills(clip, count, seeds=3):
    """For warm runs of ``clip`` from each of ``seeds`` seeds, how far the last frame's PSNR at sigma 4 px lies below
    the median of ``seeds`` stills of it (``halftone_torus``)."""
    last = clip[-1]
    stills = [halftone_torus(last, count, threads=1, seed=seed).points for seed in range(seeds)]
    reference = np.median([psnr(*exact_blurs(last, still, 4.0)) for still in stills])
    below = []
    for seed in range(seeds):
        done = []
        stipple_video(enumerate(clip), VideoSettings(n_points=count, threads=1, seed=seed), on_frame=done.append)
        below.append(reference - psnr(*exact_blurs(last, done[-1].points, 4.0)))
    return below


def test_the_cold_first_frame_is_as_good_as_a_still_where_a_viewer_looks():
    # Frame 0 is solved as a still is. In the flat metric of the warm frames, 600 dots on this photo fell 2.0 / 3.2
    # / 5.5 dB below the median of three stills at sigma 4 px (seeds 0, 1, 2), and the warm frames kept that.
    assert max(last_frames_below_stills(camera_to_coins((64, 96), [0.0]), 600)) < 3


def test_the_first_warm_frame_of_a_fade_is_corrected_up_to_the_blurs_reach():
    # The plain E_N level at N / 6 reaches 11 cycles along the short side of 208 x 128 px, where a blur of 4 px
    # still sees 18; with it alone the first warm frame of this fade lay 2.8 / 4.3 / 2.4 dB below the stills
    # (seeds 0, 1, 2; 3.7 / 4.2 / 4.2 with every frame in the density-scaled metric). A level at N / 5 before it:
    # 1.4 / 1.5 / 2.0.
    assert max(last_frames_below_stills(camera_to_coins((128, 208), [0.0, 1 / 15]), 2000)) < 3


def light_with_blobs(frames, width=200, height=120):
    """Darkness of a light page (0.06) with a still dark ring and three small dark blobs that move, grow and shrink,
    their ink scaled so that every frame holds frame 0's (a held-out review's clip)."""
    y, x = np.mgrid[0:height, 0:width] + 0.5
    page = 0.06 + 0.85 * np.exp(-(((np.hypot(x - 165, y - 60) - 18) / 2.5) ** 2))
    blobs = ((30, 30, 1.5, 0.5, 3.0, 0.35), (60, 85, 1.0, -1.0, 7.0, -0.3), (95, 40, -1.2, 1.2, 4.0, 0.15))
    inks = [
        sum(
            np.exp(-((x - x0 - vx * k) ** 2 + (y - y0 - vy * k) ** 2) / (2 * (s0 + ds * k) ** 2))
            for x0, y0, vx, vy, s0, ds in blobs
        )
        for k in range(frames)
    ]
    return [np.clip(page + 0.9 * ink * inks[0].sum() / ink.sum(), 0, 0.97) for ink in inks]


def test_a_warm_frame_on_a_light_page_is_as_good_as_a_still_where_a_viewer_looks():
    # In the flat metric the first warm frame lay up to 11.6 dB below the median of three stills at sigma 4 px
    # (seeds 0-2; 4.6 in the scaled metric with 8 pinned iterations): a still solves in the density-scaled metric,
    # where the sparse dots of a light page take steps as long as their spacing; now every frame does.
    assert max(last_frames_below_stills(light_with_blobs(2), 2000)) < 3


def test_moving_dots_follow_the_disc():
    clip = moving_disc()
    _, frames = stippled(clip)
    rows, columns = clip[0].shape
    y, x = np.mgrid[0:rows, 0:columns] + 0.5
    for k in (0, len(clip) - 1):
        centre = np.array([columns * (0.2 + 0.1 * k), 0.75 * rows])
        inside = np.hypot(*(frames[k].points * [columns, rows] - centre).T) < 0.1 * rows
        # The disc's share of the frame's ink: 18.5 dots, 1.96 x the average over its area. (The test asked for
        # 2 x the average, 18.8, more than the share itself: 18-21 dots passed or failed by chance.)
        darkness = 1 - clip[k]
        share = COUNT * darkness[np.hypot(x - centre[0], y - centre[1]) < 0.1 * rows].sum() / darkness.sum()
        assert share > 1.5 * COUNT * np.pi * (0.1 * rows) ** 2 / (rows * columns)  # a disc denser than average
        assert inside.sum() > 0.8 * share


def test_a_stop_during_the_correction_drops_the_frame():
    # Without pinned iterations a warm frame's first CG state is the pinned phase's start; the next ones are the
    # correction's (the deformation's, then the levels').
    done, calls = [], []

    def stop_in_the_correction(state):
        calls.extend([state] if len(done) == 1 else [])
        return len(calls) == 2

    settings = VideoSettings(n_points=COUNT, bandwidth=BANDWIDTH, threads=1, frame_iterations=0)
    result = stipple_video(
        enumerate(1 - g for g in moving_disc(3)), settings, on_frame=done.append, stop=stop_in_the_correction
    )
    assert result.status == "stopped" and result.frames == 1 and len(done) == 1 and len(calls) == 2


def test_a_resumed_run_gives_the_uninterrupted_runs_dots(tmp_path):
    clip = moving_disc(5)
    _, whole = stippled(clip)
    checkpoint = tmp_path / "run.ckpt"
    seen = []

    def stop_in_frame_three(state):
        seen.append(state)
        return len(seen) > 0 and len(done) == 3

    done = []
    settings = VideoSettings(n_points=COUNT, bandwidth=BANDWIDTH, threads=1)
    gray = [1 - g for g in clip]
    stopped = stipple_video(
        enumerate(gray), settings, on_frame=done.append, stop=stop_in_frame_three, checkpoint=checkpoint
    )
    assert stopped.status == "stopped" and stopped.frames == 3
    resumed = []
    result = stipple_video(enumerate(gray), settings, on_frame=resumed.append, checkpoint=checkpoint, resume=True)
    assert result.status == "finished" and result.optimised == 2
    assert [f.replayed for f in resumed] == [True, True, True, False, False]
    for a, b in zip(whole, resumed, strict=True):
        assert np.array_equal(a.points, b.points)
    with pytest.raises(StippleError, match="another input"):
        stipple_video(enumerate([1 - g[::-1] for g in clip]), settings, checkpoint=checkpoint, resume=True)


def test_a_checkpoint_of_another_warm_method_is_refused(tmp_path, monkeypatch):
    # A checkpoint written before the warm frames' metric changed resumed without a word, and its replayed frames
    # were of the other method's quality (a code review).
    from stipple import video_keeper

    clip, checkpoint = [1 - g for g in moving_disc(3)], tmp_path / "run.ckpt"
    settings = VideoSettings(n_points=COUNT, bandwidth=BANDWIDTH, threads=1)
    monkeypatch.setattr(video_keeper, "WARM_METHOD", 1)
    stipple_video(enumerate(clip[:2]), settings, checkpoint=checkpoint)
    monkeypatch.undo()
    with pytest.raises(StippleError, match="warm_method was 1, now 2"):
        stipple_video(enumerate(clip), settings, checkpoint=checkpoint, resume=True)


def frames_folder(folder, clip):
    folder.mkdir()
    for k, gray in enumerate(clip):
        Image.fromarray(np.round(gray * 255).astype(np.uint8)).save(folder / f"{k}.png")
    return folder


def video(*args):
    return CliRunner().invoke(main, ["video", *map(str, args), "-q", "--threads", "1"])


def test_a_folder_of_frames_gives_a_csv_with_dot_i_in_row_i_and_tone_true_frames(tmp_path):
    source = frames_folder(tmp_path / "in", moving_disc(5))
    (tmp_path / "f").mkdir()
    result = video(
        source, "-M", COUNT, "-N", BANDWIDTH, "--step", 2, "-o", tmp_path / "d.csv", "-o", tmp_path / "f/%03d.png"
    )
    assert result.exit_code == 0, result.output
    table = np.loadtxt(tmp_path / "d.csv", delimiter=",", skiprows=1)
    assert (tmp_path / "d.csv").read_text().startswith("frame,x,y\n")
    assert list(np.unique(table[:, 0])) == [0, 2, 4] and len(table) == 3 * COUNT
    assert sorted(p.name for p in (tmp_path / "f").iterdir()) == ["000.png", "002.png", "004.png"]
    drawn = np.asarray(Image.open(tmp_path / "f/000.png").convert("L"), float) / 255
    assert drawn.min() == 0.0  # the dark disc drawn black: tone-true dots overlap where the input is dark


def test_the_mp4_plays_with_every_frame(tmp_path):
    av = pytest.importorskip("av")
    source = frames_folder(tmp_path / "in", moving_disc(4, 62, 47))
    result = video(source, "-M", COUNT, "-N", BANDWIDTH, "--png-width", 250, "-o", tmp_path / "out.mp4")
    assert result.exit_code == 0, result.output
    with av.open(str(tmp_path / "out.mp4")) as container:
        decoded = [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)]
    assert len(decoded) == 4 and decoded[0].shape[1] == 250 and decoded[0].shape[0] % 2 == 0


def test_every_second_frame_plays_at_half_the_rate_so_the_clip_keeps_its_duration(tmp_path):
    """With --step 2 the MP4 kept the source's rate and played twice as fast (a held-out review: --step 3, 3 times)."""
    av = pytest.importorskip("av")
    path = write_mp4(tmp_path / "clip.mp4", moving_disc(4, 64, 48))  # 12 frames a second
    result = video(path, "-M", COUNT, "-N", BANDWIDTH, "--step", 2, "-o", tmp_path / "out.mp4")
    assert result.exit_code == 0, result.output
    with av.open(str(tmp_path / "out.mp4")) as container:
        assert container.streams.video[0].average_rate == 6 and container.streams.video[0].frames in (0, 2)


def write_mp4(path, clip, rate=12, codec="mpeg4"):
    av = pytest.importorskip("av")
    with av.open(str(path), "w") as container:
        stream = container.add_stream(codec, rate=rate)
        stream.height, stream.width = clip[0].shape
        stream.pix_fmt = "yuv420p"
        for gray in clip:
            rgb = np.repeat(np.round(gray * 255).astype(np.uint8)[..., None], 3, axis=2)
            container.mux(stream.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")))
        container.mux(stream.encode(None))
    return path


def test_a_video_file_is_read_frame_by_frame(tmp_path):
    path = write_mp4(tmp_path / "clip.mp4", moving_disc(4, 64, 48))
    result = video(path, "-M", COUNT, "-N", BANDWIDTH, "-o", tmp_path / "d.csv")
    assert result.exit_code == 0, result.output
    assert len(np.loadtxt(tmp_path / "d.csv", delimiter=",", skiprows=1)) == 4 * COUNT


@pytest.mark.parametrize(
    "make, outputs, message",
    [
        (lambda d: (d / "x.mp4").write_bytes(b"not a video at all") and d / "x.mp4", ["d.csv"], "x.mp4"),
        (lambda d: (d / "empty").mkdir() or d / "empty", ["d.csv"], "empty"),
        (lambda d: frames_folder(d / "in", moving_disc(2)), ["frames.png"], "%d"),
        (lambda d: frames_folder(d / "in", moving_disc(2)), ["d.txt"], "unknown video output"),
    ],
    ids=["not-a-video", "no-frames", "pattern-without-%d", "unknown-output"],
)
def test_bad_inputs_get_one_line_and_write_nothing(tmp_path, make, outputs, message):
    source = make(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    result = video(source, "-M", COUNT, *[a for o in outputs for a in ("-o", tmp_path / o)])
    assert result.exit_code != 0 and message in result.output
    assert len(result.output.strip().splitlines()) == 1, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_frame_failing_mid_way_leaves_no_output(tmp_path):
    clip = moving_disc(4)
    source = frames_folder(tmp_path / "in", clip)
    Image.new("L", (30, 30)).save(source / "3.png")  # the last frame is of another size
    (tmp_path / "f").mkdir()
    result = video(source, "-M", COUNT, "-N", BANDWIDTH, "-o", tmp_path / "d.csv", "-o", tmp_path / "f/%d.png")
    assert result.exit_code == 1 and "frame 3 is 30×30 pixels" in result.output
    assert not (tmp_path / "d.csv").exists() and not list((tmp_path / "f").iterdir())


def test_outputs_that_fail_to_open_leave_no_temporary(tmp_path, monkeypatch):
    """The CSV reserved before an MP4 that cannot be opened stayed behind as a .stipple-*.tmp."""
    import stipple.io.video

    def refused(*args):
        raise StippleError("o.mp4: cannot write the MP4")

    monkeypatch.setattr(stipple.io.video, "Mp4Stream", refused)
    plan = {"csv": [str(tmp_path / "d.csv")], "mp4": [str(tmp_path / "o.mp4")], "frames": []}
    with pytest.raises(StippleError, match="o.mp4"), stipple.io.video.VideoOutputs(plan, (10, 10), None, 24.0):
        pass
    assert not list(tmp_path.iterdir())


def test_a_broken_animated_gif_is_refused_not_cut_short(tmp_path):
    """FFmpeg decoded a truncated or corrupt GIF as far as it went, without an error: 2 or 1 of its 3 frames,
    exit 0 (a hostile sweep), where stipple torus refused the same file with Pillow's words."""
    pytest.importorskip("av")
    frames = [Image.fromarray(np.round(255 * gray).astype(np.uint8)) for gray in moving_disc(3)]
    frames[0].save(tmp_path / "whole.gif", save_all=True, append_images=frames[1:], duration=100, loop=0)
    whole = (tmp_path / "whole.gif").read_bytes()
    (tmp_path / "cut.gif").write_bytes(whole[: len(whole) // 2])
    corrupt = bytearray(whole)
    corrupt[len(whole) // 3 : len(whole) // 3 + 40] = bytes(range(40))
    (tmp_path / "corrupt.gif").write_bytes(bytes(corrupt))
    for name in ("cut.gif", "corrupt.gif"):
        result = video(tmp_path / name, "-M", 60, "-N", 12, "--iterations", 2, "-o", tmp_path / "d.csv")
        assert result.exit_code == 1 and "a broken GIF" in result.output, result.output
        assert len(result.output.strip().splitlines()) == 1 and not (tmp_path / "d.csv").exists()
    result = video(tmp_path / "whole.gif", "-M", 60, "-N", 12, "--iterations", 2, "-o", tmp_path / "d.csv")
    assert result.exit_code == 0, result.output
    assert len((tmp_path / "d.csv").read_text().splitlines()) == 1 + 3 * 60


def test_a_signal_while_a_resumed_run_replays_its_frames_lets_them_be_written(tmp_path):
    """A resumed run writes its checkpoint's frames again before any optimiser step: a first signal then only asks
    it to stop, as once the optimiser runs (a code review: after the change that lets a first signal stop a run
    still reading its input at once, the replayed frames were thrown away)."""
    import subprocess
    import sys

    from test_safety_signals import CHILD

    source = frames_folder(tmp_path / "in", moving_disc(6))
    common = ["video", str(source), "-M", str(COUNT), "-N", str(BANDWIDTH), "-q", "--threads", "1"]
    checkpoint = ["--checkpoint", str(tmp_path / "run.npz")]
    assert video(*common[1:-3], *checkpoint, "--stop", 3, "-o", tmp_path / "a.csv").exit_code == 0
    (tmp_path / "f").mkdir()
    outputs = ["-o", str(tmp_path / "b.csv"), "-o", str(tmp_path / "f/%d.png")]
    # The resumed run fsyncs the CSV's reserved temporary, then the first replayed frame's PNG: SIGINT right after.
    arguments = [sys.executable, "-c", CHILD, "fsync", "2", "SIGINT", *common, *checkpoint, "--resume", *outputs]
    done = subprocess.run(arguments, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 130 and "outputs written" in done.stderr, done.stderr
    assert len((tmp_path / "b.csv").read_text().splitlines()) >= 1 + 3 * COUNT
    assert {path.name for path in (tmp_path / "f").iterdir()} >= {"0.png", "1.png", "2.png"}


def test_an_mp4_whose_stream_failed_to_open_closes(tmp_path):
    """The container was open but its stream was not: close() then raised AttributeError (on None.encode) over the
    first error (a hostile --fps nan, now refused where it enters)."""
    pytest.importorskip("av")
    from stipple.io.mp4 import Mp4Stream

    movie = Mp4Stream(str(tmp_path / "o.mp4.tmp"), str(tmp_path / "o.mp4"), float("nan"))
    with pytest.raises(ValueError):
        movie.write(Image.new("RGB", (8, 8)))
    movie.close()
    assert movie.container is None


def test_a_faint_clip_gets_the_torus_note_once_before_its_first_frame(tmp_path):
    """stipple video said none of the notes stipple torus gives on the same frame (a held-out review)."""
    faint = [0.4 + 0.2 * gray for gray in moving_disc(3)]  # gray values spanning a fifth of the range
    source = frames_folder(tmp_path / "in", faint)
    args = ["video", str(source), "-M", COUNT, "-N", BANDWIDTH, "--threads", "1", "-o", str(tmp_path / "d.csv")]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    assert result.output.count("gray values span only") == 1, result.output
    assert "gray values span" not in CliRunner().invoke(main, [*args, "-q"]).output


def test_a_folder_where_a_later_frame_goes_leaves_every_output_as_it_was(tmp_path):
    source = frames_folder(tmp_path / "in", moving_disc(4))
    (tmp_path / "f/2.png").mkdir(parents=True)  # only frame 2's file cannot be written
    (tmp_path / "d.csv").write_text("old\n")
    result = video(source, "-M", COUNT, "-N", BANDWIDTH, "-o", tmp_path / "d.csv", "-o", tmp_path / "f/%d.png")
    assert result.exit_code == 1 and "f/2.png: cannot write (it is a folder)" in result.output
    assert (tmp_path / "d.csv").read_text() == "old\n"
    assert sorted(p.name for p in (tmp_path / "f").iterdir()) == ["2.png"]
    assert not leftovers(tmp_path)


def test_a_full_disk_during_the_run_names_the_output_and_leaves_no_temporary(tmp_path):
    pytest.importorskip("av")
    source = frames_folder(tmp_path / "in", moving_disc(4))
    limit = lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))  # noqa: E731  (bytes per file)
    args = ["video", source, "-M", COUNT, "-N", BANDWIDTH, "-q", "-o", "d.csv", "-o", "v.mp4"]  # the CSV: 40 kB
    result = stipple_process(args, tmp_path, preexec_fn=limit)
    assert result.returncode == 1 and result.stderr.strip() == "Error: d.csv: cannot write (File too large)"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in"] and not leftovers(tmp_path)


def test_only_dots_near_a_change_are_free_and_the_margin_wraps_around():
    settings = VideoSettings(n_points=1200, change=0.02, free_margin=3.0)
    rows, columns = 40, 60
    spacing = np.sqrt(2 * rows * columns / (np.sqrt(3) * 1200))  # 1.41 pixels
    reference = np.full((rows, columns), 0.5)
    weights = reference.copy()
    weights[18:22, 0:3] = 1.0  # a change at the left edge
    y, x = np.mgrid[0:rows, 0:columns] + 0.5
    points = np.column_stack([x.ravel() / columns, y.ravel() / rows])
    free, updated = free_dots(points, reference, weights, settings)
    distance = np.hypot(np.minimum(np.abs(x - 1.5), columns - np.abs(x - 1.5)), np.abs(y - 20)).ravel()
    assert free[distance < 3].all() and not free[distance > 3 + 3 * spacing + 4].any()
    assert free[(x.ravel() > columns - 3) & (np.abs(y.ravel() - 20) < 2)].all()  # across the wrap
    assert np.array_equal(updated.ravel()[free], weights.ravel()[free])
    assert np.array_equal(updated.ravel()[~free], reference.ravel()[~free])
    unchanged, _ = free_dots(points, reference, reference + 0.01, settings)  # below the change threshold
    assert not unchanged.any()


def test_an_unchanged_frame_keeps_every_dot_and_a_key_frame_starts_a_chunk():
    clip = moving_disc(3)
    _, frames = stippled([clip[0], clip[0], clip[1]])
    assert frames[1].iterations == 0 and np.array_equal(frames[1].points, frames[0].points)
    assert not np.array_equal(frames[2].points, frames[1].points)
    _, chunk = stippled([clip[1]], key=(frames[1].points, 1 - clip[0]))
    assert chunk[0].warm and np.array_equal(chunk[0].points, frames[2].points)


def test_a_file_without_a_decodable_video_stream_gets_one_line(tmp_path):
    av = pytest.importorskip("av")
    audio = tmp_path / "audio.mp4"
    with av.open(str(audio), "w") as container:
        stream = container.add_stream("aac", rate=8000)
        frame = av.AudioFrame.from_ndarray(np.zeros((1, 1024), dtype=np.float32), format="fltp", layout="mono")
        frame.sample_rate = 8000
        for packet in [*stream.encode(frame), *stream.encode(None)]:
            container.mux(packet)
    truncated = tmp_path / "truncated.mp4"
    truncated.write_bytes(write_mp4(tmp_path / "clip.mp4", moving_disc(2)).read_bytes()[:200])
    for path, message in ((audio, "no video stream"), (truncated, "not a video PyAV can read")):
        result = video(path, "-M", COUNT, "-o", tmp_path / "d.csv")
        assert result.exit_code == 1 and message in result.output and len(result.output.splitlines()) == 1
    assert not (tmp_path / "d.csv").exists()


def colour_disc(frames=4, width=64, height=48):
    """RGB frames in [0, 1]: a still band from cyan to yellow above a red disc moving right over light blue."""
    y, x = np.mgrid[0:height, 0:width] + 0.5
    t = x / width
    still = np.stack([t, np.full_like(t, 0.8), 1 - t], axis=-1)
    clip = []
    for k in range(frames):
        cover = np.clip(6.5 - np.hypot(x - width * (0.25 + 0.1 * k), y - 0.7 * height), 0, 1)[..., None]
        moving = np.array([0.7, 0.85, 1.0]) * (1 - cover) + np.array([0.9, 0.1, 0.1]) * cover
        clip.append(np.where((y < 0.4 * height)[..., None], still, moving))
    return clip


def test_a_colour_video_keeps_each_dot_in_its_ink_and_each_ink_as_good_as_a_cold_run():
    from stipple.colour import halftone_colour, separate

    clip = colour_disc()
    frames = []
    settings = VideoSettings(n_points=COUNT, bandwidth=BANDWIDTH, threads=1, palette="cmy")
    stipple_video(enumerate(clip), settings, on_frame=frames.append)
    assert [name for name, _, _ in frames[0].inks] == ["cyan", "magenta", "yellow"]
    assert all(frame.inks == frames[0].inks for frame in frames)  # dot i is the same ink's in every frame
    rows, columns = clip[0].shape[:2]
    spacing = np.sqrt(2 / (np.sqrt(3) * COUNT / (rows * columns)))
    for before, after in zip(frames, frames[1:], strict=False):
        still = before.points[:, 1] * rows < 0.3 * rows  # the still band, away from the disc
        moves = np.hypot(*((after.points - before.points)[still] * [columns, rows]).T) / spacing
        assert np.median(moves) < 0.05 and np.percentile(moves, 95) < 0.2
    # Against the median of three cold runs: at 400 dots one cold run's error scatters by up to 1.55 x from seed to
    # seed, and the video's own cold frame 0 lies 1.42 x above the median in its cyan.
    for frame, rgb in zip(frames, clip, strict=True):
        inks = {layer.name: layer.density for layer in separate(rgb, "cmy")}
        colds = [
            halftone_colour(
                rgb, COUNT, BANDWIDTH, separation="cmy", threads=1, init="density", settle=1.5e-3, seed=seed
            )
            for seed in range(3)
        ]
        for index, (name, _, part) in enumerate(frame.inks):
            cold_errors = [rms_blur_error(inks[name], cold.points[problem.slices[index]]) for _, problem, cold in colds]
            assert rms_blur_error(inks[name], frame.points[part]) < 1.5 * np.median(cold_errors), name


def test_a_colour_videos_warm_frames_keep_the_inks_dots_apart():
    """A held-out review (a blue disc moving 12 px a frame over the coffee photo): the plain E_N levels of the warm
    correction moved each ink's dots by its own term's gradient, and dots of different inks slid onto each other,
    45-130 dots a frame in coincident pairs (nearer than 0.3 of their six nearest neighbours' mean distance) where a
    cold frame has none, p01 0.20-0.30 against a still's 0.70. Colour frames now skip those levels."""
    from scipy.spatial import cKDTree
    from skimage import data, transform

    photo = transform.resize(data.coffee() / 255.0, (112, 160), anti_aliasing=True)
    y, x = np.mgrid[0:112, 0:160] + 0.5
    clip = []
    for k in range(4):
        disc = np.clip(12.5 - np.hypot(x - 30 - 12 * k, y - 56), 0, 1)[..., None]
        clip.append(photo * (1 - disc) + np.array([0.1, 0.35, 0.9]) * disc)
    frames = []
    stipple_video(enumerate(clip), VideoSettings(n_points=3000, threads=1, palette="cmyk"), on_frame=frames.append)
    for frame in frames:
        pixels = frame.points * [160, 112]
        distances = cKDTree(pixels).query(pixels, 7)[0][:, 1:]
        coincident = np.sum(distances[:, 0] < 0.3 * distances.mean(axis=1))
        assert coincident <= 15, (frame.index, coincident)  # 0.5 % (now 0-10; with the levels 53 and 24)


def rms_blur_error(density, points, sigma=4.0):
    """The root mean square of the exactly blurred dots' error against the blurred density."""
    return float(np.sqrt(np.mean(np.subtract(*exact_blurs(density, points, sigma)) ** 2)))


def test_fixed_class_counts_give_each_ink_its_share_of_the_union():
    from stipple.multiclass import multiclass_problem
    from stipple.torus_spectrum import axis_bandwidths, image_coefficients

    y, x = np.mgrid[0:32, 0:48] / 48
    densities = [0.2 + 0.5 * x, 0.6 - 0.3 * y]
    counts = [100, 200]  # not in proportion to the masses
    problem = multiclass_problem(densities, 300, 16, counts=counts, threads=1, near_field=False)
    assert [part.n_points for part in problem.classes] == counts
    masses = np.array([d.sum() for d in densities])
    shares = np.array(counts) / 300 * masses.sum() / masses
    bandwidths = axis_bandwidths(16, densities[0].shape)
    expected = sum(s * image_coefficients(d, bandwidths) for s, d in zip(shares, densities, strict=True))
    assert np.allclose(problem.discrepancy.target, expected, rtol=1e-12, atol=1e-15)
    assert np.isclose(problem.discrepancy.weight * 300, masses.sum() / densities[0].size)  # the inks' mass
    with pytest.raises(StippleError, match="class counts"):
        multiclass_problem(densities, 300, 16, counts=[100, 100], threads=1)


def test_colour_video_command_writes_each_dots_ink_and_refuses_gray_options(tmp_path):
    source = tmp_path / "in"
    source.mkdir()
    for k, rgb in enumerate(colour_disc(3)):
        Image.fromarray(np.round(rgb * 255).astype(np.uint8)).save(source / f"{k}.png")
    result = video(source, "-M", COUNT, "-N", BANDWIDTH, "--palette", "cmy", "-o", tmp_path / "d.csv")
    assert result.exit_code == 0, result.output
    lines = (tmp_path / "d.csv").read_text().splitlines()
    assert lines[0] == "frame,x,y,layer" and len(lines) == 1 + 3 * COUNT
    inks = [[line.split(",")[3] for line in lines[1:] if line.startswith(f"{k},")] for k in range(3)]
    assert inks[0] == inks[1] == inks[2] and set(inks[0]) == {"cyan", "magenta", "yellow"}
    refused = video(source, "-M", COUNT, "--palette", "cmy", "--levels", "auto", "-o", tmp_path / "e.csv")
    assert refused.exit_code != 0 and "--levels" in refused.output and not (tmp_path / "e.csv").exists()


def test_a_gray_palette_video_prints_each_frames_luminance(tmp_path):
    """As ``stipple colour --palette gray``: one black ink's tone is the frame's luminance, not the mean of its
    channels (a saturated blue, luminance 0.21, was drawn 0.34 in every frame)."""
    pixels = np.zeros((16, 24, 3), dtype=np.uint8)
    pixels[:, :12], pixels[:, 12:] = (20, 40, 200), (230, 210, 20)  # luminance 0.21 and 0.76
    source = tmp_path / "in"
    source.mkdir()
    for k in range(2):
        Image.fromarray(pixels).save(source / f"{k}.png")
    (tmp_path / "f").mkdir()
    result = video(source, "-M", 1200, "--palette", "gray", "--iterations", 30, "-o", tmp_path / "f/%d.png")
    assert result.exit_code == 0, result.output
    luminance = pixels[0] / 255 @ [0.299, 0.587, 0.114]
    for k in range(2):
        drawn = (
            np.asarray(Image.open(tmp_path / f"f/{k}.png").convert("RGB"), dtype=float) / 255 @ [0.299, 0.587, 0.114]
        )
        columns = drawn.shape[1]
        for part, wanted in ((slice(3, 9), luminance[0]), (slice(15, 21), luminance[-1])):
            half = drawn[:, part.start * columns // 24 : part.stop * columns // 24]
            assert abs(half.mean() - wanted) < 0.03, (k, half.mean(), wanted)


def test_levels_stretch_every_frame_alike(tmp_path):
    from stipple.io.images import load_density
    from stipple.io.video import open_frames

    source = frames_folder(tmp_path / "in", moving_disc(3))
    frames = open_frames(source)
    fixed = dict(frames.densities(levels=(0.2, 0.8)))
    assert np.array_equal(fixed[2], load_density(source / "2.png", levels=(0.2, 0.8)))
    first = load_density(source / "0.png")
    black, white = np.percentile(1 - first, [0.5, 99.5])
    auto = dict(frames.densities(levels="auto"))
    assert np.array_equal(auto[2], load_density(source / "2.png", levels=(black, white)))


def test_a_cut_reruns_the_changed_part_and_leaves_the_still_part_alone():
    rows, columns = 64, 64
    rng = np.random.default_rng(3)
    textures = [gaussian_filter(rng.random((36, columns)), 4.0, mode="wrap") for _ in range(2)]
    textures = [0.1 + 0.8 * (t - t.min()) / np.ptp(t) for t in textures]
    textures[1] += textures[0].mean() - textures[1].mean()  # the same ink in both: the strip keeps its dots
    strip = np.tile(0.3 + 0.4 * (np.arange(columns) + 0.5) / columns, (rows - 36, 1))
    clip = [np.vstack([textures[k], strip]) for k in (0, 0, 1)]
    assert frame_change(clip[1], clip[2], COUNT) > CUT > frame_change(clip[0], clip[0] + 0.001, COUNT)
    _, frames = stippled([1 - c for c in clip])
    spacing = np.sqrt(2 / (np.sqrt(3) * COUNT / (rows * columns)))
    before, after = frames[1].points, frames[2].points
    still = (before[:, 1] * rows > 36 + 2 * spacing) & (before[:, 1] * rows < rows - 2 * spacing)
    moves = np.hypot(*((after - before)[still] * [columns, rows]).T) / spacing
    assert np.median(moves) < 0.05 and np.percentile(moves, 95) < 0.2
    problem = torus_problem(clip[2], COUNT, BANDWIDTH, threads=1, near_field=False)
    cold = halftone_torus(clip[2], COUNT, BANDWIDTH, threads=1).points
    assert discrepancy_energy(problem, after) < 1.3 * discrepancy_energy(problem, cold)


def test_a_colour_pan_taken_for_a_cut_stops_where_a_cold_run_would():
    """A frame whose change passes ``CUT`` runs under the cold run's stopping rule: --tol of the gradient norm at
    i.i.d. samples. Taken relative to its warm start's far smaller norm (a fast pan's frames start close to their
    minimum), the colour frames of a pan ran longer than the cold frame itself."""
    rng = np.random.default_rng(5)
    texture = gaussian_filter(rng.random((48, 64, 3)), (2, 2, 0), mode="wrap")
    first = np.clip((texture - texture.min()) / np.ptp(texture) * 1.2 - 0.1, 0, 1)
    clip = [first, np.roll(first, 3, axis=1)]
    assert frame_change(*(1 - np.moveaxis(c, -1, 0) for c in clip), COUNT) > CUT
    frames = []
    settings = VideoSettings(n_points=COUNT, bandwidth=BANDWIDTH, threads=1, palette="cmy")
    stipple_video(enumerate(clip), settings, on_frame=frames.append)
    assert frames[1].warm and frames[1].iterations < frames[0].iterations, [f.iterations for f in frames]


def test_pen_dot_frames_are_placed_by_the_darkness_clipped_at_the_pen_reach(tmp_path):
    """Point dots of a 0.5 mm pen on a dark clip: placed by the unclipped darkness, the drawing had to leave out
    368-452 of 2500 dots per frame where they would touch; placed as a still's are, almost none."""
    rows, columns = np.mgrid[0:48, 0:72]
    clip = [
        np.where((columns - 20 - 3 * k) ** 2 + (rows - 24) ** 2 < 81, 0.02, 0.05 + 0.6 * columns / 72) for k in range(2)
    ]
    source = frames_folder(tmp_path / "in", clip)
    (tmp_path / "f").mkdir()
    pen = ["--dot-style", "point", "--pen-width", "0.5mm", "--width", "40mm"]
    result = video(source, "-M", 2500, *pen, "-o", tmp_path / "f/%d.svg")
    assert result.exit_code == 0, result.output
    for k in range(2):
        drawn = (tmp_path / f"f/{k}.svg").read_text().count("<path ")
        assert 2500 - 25 <= drawn <= 2500


@pytest.mark.parametrize("palette", [None, "cmy"])
def test_frames_are_placed_by_the_settings_placement_each_ink_keeping_its_share(palette):
    """``VideoSettings.placement`` (a pen's clip) acts on every frame's darkness, on a colour frame's inks
    together: each ink keeps its share of the placed darkness at every pixel."""
    from stipple.colour import separate

    clip = colour_disc(frames=2)
    pictures = clip if palette else [1 - rgb @ np.array([0.299, 0.587, 0.114]) for rgb in clip]
    settings = VideoSettings(
        n_points=300,
        bandwidth=24,
        threads=1,
        palette=palette,
        iterations=5,
        frame_iterations=2,
        placement=lambda w: np.minimum(w, 0.4),
    )
    frames = []
    stipple_video(enumerate(pictures), settings, on_frame=frames.append)
    for picture, frame in zip(pictures, frames, strict=True):
        if palette is None:
            assert np.array_equal(frame.density, np.minimum(picture, 0.4))
            continue
        inks = np.stack([layer.density for layer in separate(picture, palette)])
        union = inks.sum(axis=0)
        assert frame.density.sum(axis=0) == pytest.approx(np.minimum(union, 0.4), abs=1e-12)
        share = np.divide(inks, union, out=np.zeros_like(inks), where=union > 0)
        placed = np.divide(frame.density, frame.density.sum(axis=0), out=np.zeros_like(inks), where=union > 0)
        assert placed == pytest.approx(share, abs=1e-12)


def test_a_dark_disc_moving_through_its_dots_leaves_no_holes():
    """A dark disc moving down 5 px a frame over a flat band: the deformation shifted its dots as a whole and left
    gaps where they met the freed dots, white holes in the disc (blurred at 1 px, 0.20 where the cold frame has
    0.08). The freed dots' iterations after the deformation close them."""
    from stipple.io.writers import drawing_bytes
    from stipple.render.flat import torus_drawing

    height, width = 120, 160
    rows, columns = np.mgrid[0:height, 0:width]

    def disc_centre(k):
        return 60, 20 + 5 * k

    def darkness(k):
        x, y = disc_centre(k)
        luminance = np.where((columns >= 40) & (columns <= 80), 0.6, 0.35 + 0.6 * columns / (width - 1))
        return 1 - np.where((columns - x) ** 2 + (rows - y) ** 2 < 14**2, 0.05, luminance)

    frames = []
    stipple_video(((k, darkness(k)) for k in range(3)), VideoSettings(n_points=8000, threads=1), on_frame=frames.append)
    lightest = []
    for frame in frames:
        drawing = torus_drawing(frame.points, (height, width), darkness=frame.density, png_width=4 * width)
        picture = Image.open(io.BytesIO(drawing_bytes(drawing, ".png"))).convert("F").resize((width, height), Image.BOX)
        x, y = disc_centre(frame.index)
        inside = (columns - x) ** 2 + (rows - y) ** 2 <= 11**2
        lightest.append(gaussian_filter(np.asarray(picture) / 255, 1.0)[inside].max())
    assert max(lightest[1:]) <= 1.5 * lightest[0], lightest


def test_range_is_refused_for_image_frames(tmp_path):
    """Image frames: --range (the .npy maps') was accepted and ignored."""
    source = frames_folder(tmp_path / "in", moving_disc(2))
    result = video(source, "-M", COUNT, "--range", "0", "1", "-o", tmp_path / "d.csv")
    assert result.exit_code == 1 and "--range is for .npy frames" in result.output


def test_levels_auto_takes_the_stills_rule_on_the_first_frame(tmp_path):
    """``--levels auto`` is ``auto_levels`` of the first frame, as for a still: a page with one small mark (one gray
    at both percentiles) was refused with a message about BLACK,WHITE."""
    folder = tmp_path / "frames"
    folder.mkdir()
    page = np.full((32, 48), 247, dtype=np.uint8)
    page[10:13, 20:23] = 13
    for index in range(2):
        Image.fromarray(page).save(folder / f"{index}.png")
    result = video(folder, "-M", 60, "--levels", "auto", "--iterations", 2, "-o", tmp_path / "v.csv")
    assert result.exit_code == 0, result.output


def test_bandwidth_zero_is_refused_as_torus_refuses_it(tmp_path):
    """``-N 0`` ran with the default bandwidth (``bandwidth or default``); ``stipple torus`` refuses it."""
    source = frames_folder(tmp_path / "in", moving_disc(2))
    result = video(source, "-M", COUNT, "-N", 0, "-o", tmp_path / "d.csv")
    assert result.exit_code == 1 and "bandwidth must be an even integer in [2, 8192], not 0" in result.output
    assert not (tmp_path / "d.csv").exists()


def test_a_blank_colour_frame_is_named(tmp_path):
    """A colour video's blank frame said 'the image is blank' without the frame (a gray one names it)."""
    source = tmp_path / "in"
    source.mkdir()
    for k, colour in enumerate([(0, 200, 200), (200, 0, 0), (255, 255, 255)]):
        Image.new("RGB", (40, 30), colour).save(source / f"{k}.png")
    result = video(source, "--palette", "cmyk", "-M", 60, "-N", BANDWIDTH, "-o", tmp_path / "d.csv")
    assert result.exit_code == 1 and "frame 2: " in result.output and "blank" in result.output


def test_a_source_rate_no_mp4_plays_is_refused_unless_fps_is_given(tmp_path):
    """A clip whose metadata said 240000 frames a second gave an MP4 that played no frame, exit 0 (a hostile
    review); --fps is bounded by 1000, the source's rate was not."""
    av = pytest.importorskip("av")
    noise = list(np.random.default_rng(0).random((3, 32, 32)))  # the disc's frames decode to none at this rate
    path = write_mp4(tmp_path / "fast.mp4", noise, rate=240000, codec="libx264")
    result = video(path, "-M", COUNT, "-N", BANDWIDTH, "-o", tmp_path / "out.mp4")
    assert result.exit_code == 1 and "more than 1000, which an MP4 does not play; give --fps" in result.output
    assert not (tmp_path / "out.mp4").exists()
    assert video(path, "-M", COUNT, "-N", BANDWIDTH, "-o", tmp_path / "d.csv").exit_code == 0  # no MP4: no rate
    result = video(path, "-M", COUNT, "-N", BANDWIDTH, "--fps", 24, "-o", tmp_path / "out.mp4")
    assert result.exit_code == 0, result.output
    with av.open(str(tmp_path / "out.mp4")) as container:
        assert container.streams.video[0].average_rate == 24 and len(list(container.decode(video=0))) == 3


@pytest.mark.parametrize("pattern", ["%d/f.png", "run%02d/frame.svg"])
def test_the_frame_number_goes_in_the_file_name_not_a_folder(tmp_path, pattern):
    """With %d in a folder only the first frame's folder was checked before the run: a missing one for frame 1
    failed after every frame was made, a read-only one was written into by root (a hostile review)."""
    from stipple.errors import StippleError
    from stipple.io.video import check_frame_pattern

    with pytest.raises(StippleError, match="the frame number goes in the file name, not in a folder"):
        check_frame_pattern(str(tmp_path / pattern))
    assert check_frame_pattern("100%%/f_%d.png") == "100%%/f_%d.png"  # a literal '%' in a folder is fine


@pytest.mark.parametrize("name", ["vo/%03d.csv", "%d.mp4"])
def test_a_frame_number_in_a_csv_or_mp4_name_is_refused(name):
    """'vo/%03d.csv' was written under that very name (a fifth sweep): one CSV or MP4 holds every frame."""
    from stipple.io.video import plan_outputs

    with pytest.raises(StippleError, match="holds every frame; a %d pattern is for one PNG or SVG per frame"):
        plan_outputs([name])
    assert plan_outputs(["100%%.csv", "-"])["csv"] == ["100%%.csv", "-"]  # a literal name otherwise


def test_npy_frames_share_one_stretch_so_a_fading_map_fades(tmp_path):
    """Each .npy frame was stretched to its own least and greatest value: a ramp fading to nearly even (0.9-1.0)
    was stippled as the same ramp, and --range was refused (a hostile review). One stretch for the clip now; the
    faded frame's dots spread evenly."""
    source = tmp_path / "maps"
    source.mkdir()
    ramp = np.mgrid[0:20, 0:30][1] / 29.0
    np.save(source / "0.npy", ramp)
    np.save(source / "1.npy", 0.9 + 0.1 * ramp)
    for extra in ([], ["--range", "0", "1"]):
        result = video(source, "-M", 60, "-N", 12, *extra, "-o", tmp_path / "d.csv")
        assert result.exit_code == 0, result.output
        table = np.loadtxt(tmp_path / "d.csv", delimiter=",", skiprows=1)
        ramped, faded = (table[table[:, 0] == frame, 1].mean() for frame in (0, 1))
        assert ramped > 19 and abs(faded - 15) < 1  # 2/3 of the width under a ramp; the middle when even


def test_a_pipe_as_the_video_is_refused_at_once(tmp_path):
    """A FIFO without a writer blocked for ever (a signal then said 'not a video'), and a pipe cannot be read
    twice, as the first frame and the run read it."""
    import os
    import subprocess
    import sys

    os.mkfifo(tmp_path / "clip.mp4")
    command = [sys.executable, "-m", "stipple", "video", "clip.mp4", "-M", str(COUNT), "-q", "-o", "d.csv"]
    result = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=60)  # it waited for ever
    assert result.returncode == 1 and "not a regular file (a pipe?)" in result.stderr


def test_levels_on_npy_frames_is_refused_as_for_a_still_map(tmp_path):
    """With the clip-wide range the frames were read leniently, and --levels on .npy frames was ignored (a code
    review); a still map refuses it."""
    source = tmp_path / "maps"
    source.mkdir()
    for index in range(2):
        np.save(source / f"{index}.npy", np.mgrid[0:20, 0:30][1] / 29.0 + index)
    result = video(source, "-M", 60, "-N", 12, "--levels", "0.1,0.9", "-o", tmp_path / "d.csv")
    assert result.exit_code == 1 and "--levels is for images; a .npy map is stretched by --range" in result.output


def test_a_broken_file_named_as_an_image_is_called_broken_and_a_good_one_an_image(tmp_path):
    """An empty `x.png` given to video was "an image, not a video" by its name alone (a hostile sweep)."""
    (tmp_path / "empty.png").write_bytes(b"")
    (tmp_path / "text.png").write_text("not a picture\n")
    Image.fromarray(np.full((8, 8), 90, np.uint8)).save(tmp_path / "gray.png")
    for name, message in (("empty", "file is empty"), ("text", "cannot decode image"), ("gray", "an image, not")):
        result = CliRunner().invoke(main, ["video", str(tmp_path / f"{name}.png"), "-o", str(tmp_path / "a.csv")])
        assert result.exit_code == 1 and message in result.output, result.output
