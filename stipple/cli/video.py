"""``stipple video``: a video or a sequence of frames stippled with the same dots, frame after frame."""

import itertools
import sys
import time

import click

from ..errors import StippleError
from . import supervise
from .defaults import FRAME_ITERATIONS
from .options import (
    backend_option,
    common_options,
    init_input,
    palette_options,
    parse_levels,
    render_settings,
    resolve_input,
    without,
)
from .supervise import SIGNALS, Progress, checkpoint_interval, guarded_files
from .torus import tone_hints
from .values import FiniteFloatRange, IntegerRange

DEFAULT_FPS = 24.0
MIN_FPS, MAX_FPS = 0.01, 1000.0


@click.command()
# Dot i stays dot i in every frame, so nothing is reordered; the run reports frames, not settings.
@without("order", "verbose")
@click.argument("source", required=False)
@common_options
@click.option("--init", default="stratified", show_default=True, help="Frame 0's start (as for 'stipple torus').")
@backend_option()
@click.option(
    "--hessian",
    type=click.Choice(["gauss-newton", "full"]),
    default="gauss-newton",
    show_default=True,
    help="Hessian of the Newton step.",
)
@click.option(
    "--correct/--no-correct",
    default=True,
    show_default=True,
    help="The low-frequency correction: frame 0's, and the smooth deformation and levels of every later frame "
    "whose darkness changed.",
)
@click.option(
    "--frame-iterations",
    type=IntegerRange(min=0),
    default=FRAME_ITERATIONS,
    show_default=True,
    help="CG iterations of every frame after the first (each starts from the previous frame's dots), before its "
    "correction (4 more after its deformation).",
)
@click.option(
    "--fps",
    type=FiniteFloatRange(min=MIN_FPS, max=MAX_FPS),
    default=None,
    help=f"MP4 frame rate (default: the video's, or {DEFAULT_FPS:g} for images, over --step: the same duration).",
)
@click.option("--start", type=IntegerRange(min=0), default=0, show_default=True, help="First frame (from 0).")
@click.option("--stop", type=IntegerRange(min=1), default=None, help="Stop before this frame (default: the end).")
@click.option("--step", type=IntegerRange(min=1), default=1, show_default=True, help="Take every STEP-th frame.")
@click.option(
    "--levels",
    default=None,
    help="Gray values BLACK,WHITE in [0, 1] stretched to black and white before stippling, or 'auto' (the first "
    "frame's 0.5th and 99.5th percentiles, or its extremes where those would clip a spot; kept for every frame).",
)
@palette_options(None)
@click.pass_context
def video(ctx, source, **options):
    """Stipple SOURCE, a video (MP4, MOV, WebM, GIF, ...; needs stipple[video]) or a folder or glob of frame
    images, with the same dots in every frame: -o out.mp4, -o dots.csv (frame,x,y; row i of every frame is dot
    i), -o 'frames/%04d.png' (one PNG or SVG per frame). With --palette, one layer of dots per ink, each dot
    keeping its ink (CSV frame,x,y,layer)."""
    from ..colour import parse_palette
    from ..io.png import check_png_outputs
    from ..io.video import VideoOutputs, check_frames_spare_inputs, frame_path, open_frames, plan_outputs
    from ..pipelines.outputs import torus_files

    started = time.perf_counter()
    source = resolve_input(ctx, source)
    if source is None:
        raise click.UsageError("missing SOURCE (or 'input' in --config)")
    try:
        if options["palette"] is not None:
            from .recipes import check_colour_options

            check_colour_options(options)
        settings = render_settings(options)
        plan = plan_outputs(options["outputs"])
        frames = open_frames(source, start=options["start"], stop=options["stop"], step=options["step"])
        check_frames_spare_inputs(plan["frames"], frames)
        reports = [("MP4", path) for path in plan["mp4"]]
        reports += [("frame pattern", frame_path(path, frames.selection.start)) for path in plan["frames"]]
        # A folder's or glob's frame images are inputs too: an output linked to one of them would write it.
        inputs = [("input", source), *(("input frame", path) for path in frames.files), init_input(options["init"])]
        with guarded_files([i for i in inputs if i], plan["csv"], options["checkpoint"], reports):
            drawn = [".png"] if plan["mp4"] or any(p.lower().endswith(".png") for p in plan["frames"]) else []
            check_png_outputs(drawn, frames.shape[::-1], options["png_width"], options["n_points"])
            # Every --step-th frame shown at the source's rate over --step: the clip keeps its duration.
            fps = options["fps"] or (source_fps(frames.fps, options["step"], source) if plan["mp4"] else None)

            def draw(points, density, fmt):
                return torus_files(points, frames.shape, [fmt], settings, density)[fmt]

            if options["palette"] is not None:
                draw = colour_drawing(frames.shape, settings, parse_palette(options["palette"]))
            with VideoOutputs(plan, frames.shape, draw, fps, layered=options["palette"] is not None) as outputs:
                result, stopped_by = run_frames(
                    frames, video_settings(options, frames.shape, settings), outputs, options
                )
                if result.frames:
                    outputs.commit()
    except StippleError as error:
        raise click.ClickException(str(error)) from None
    finish(result, stopped_by, options, started)


def source_fps(rate, step, source):
    """The MP4's frame rate without --fps: the source's (``DEFAULT_FPS`` for images) over ``step``, at least
    ``MIN_FPS``; a rate past ``MAX_FPS`` is refused (a clip's metadata said 240000 a second, and its MP4 played
    no frame)."""
    fps = max((rate or DEFAULT_FPS) / step, MIN_FPS)
    if fps > MAX_FPS:
        raise StippleError(
            f"{source}: its frame rate {rate:g} a second (over --step {step}) is more than {MAX_FPS:g}, which an MP4 "
            "does not play; give --fps"
        )
    return fps


def colour_drawing(shape, settings, separation):
    """``draw(points, frame, fmt)`` of a colour video's frame: its inks' layers, as ``stipple colour`` draws them
    (``separation``: the parsed ``--palette``)."""
    from ..pipelines.colour import tone_settings
    from ..pipelines.outputs import layered_files

    settings = {key: value for key, value in settings.items() if key != "color"}

    def draw(points, frame, fmt):
        placed = [(name, colour, points[part]) for name, colour, part in frame.inks]
        tone = tone_settings(list(frame.density), frame.picture, separation)
        return layered_files(placed, shape, [fmt], settings, **tone)[fmt]

    return draw


def video_settings(options, shape, draw):
    """The library's settings from the command's options (``--init`` CSVs read for frame 0's ``shape``; ``draw``,
    the drawing's settings: pen dots are placed by the darkness clipped at the pen's reach)."""
    from functools import partial

    from ..colour import check_palette_extras, parse_palette
    from ..halftone import check_integer
    from ..pipelines.inputs import read_torus_init
    from ..pipelines.pen import placement_density
    from ..video import VideoSettings

    check_integer("seed", options["seed"], 0, 2**63 - 1)
    check_palette_extras(options["palette"], options["black"], options["union_weight"])
    palette = None if options["palette"] is None else parse_palette(options["palette"])
    return VideoSettings(
        n_points=options["n_points"],
        bandwidth=options["bandwidth"],
        backend=options["backend"],
        threads=options["threads"],
        **({} if options["epsilon"] is None else {"epsilon": options["epsilon"]}),
        hessian=options["hessian"],
        near_field=options["near_field"] is not False,
        seed=options["seed"],
        init=read_torus_init(options["init"], shape),
        tol=options["tol"],
        settle=options["settle"],
        iterations=options["iterations"],
        frame_iterations=options["frame_iterations"],
        time_limit=options["time_limit"],
        correct=options["correct"],
        safeguard=options["safeguard"],
        beta=options["beta"],
        palette=palette,
        black=options["black"],
        union_weight=options["union_weight"],
        placement=partial(placement_density, n_points=options["n_points"], draw=draw),
    )


class FrameProgress(Progress):
    """The progress bar over the ``total`` frames (off when quiet or stderr is not a TTY): shown from the start,
    since the first frame is a cold run, the longest of all, and its clock kept going within a frame."""

    def __init__(self, total, enabled):
        super().__init__(enabled)
        self.total = total
        self._refreshed = 0.0

    def start(self, resume=False):
        if self.enabled:
            self._open().set_postfix_str("replaying the checkpoint" if resume else "the first frame: a cold run")

    def watch(self, state):
        """Every CG state of the frame under way: the bar redrawn (its clock) at most twice a second."""
        if self.enabled and time.monotonic() - self._refreshed > 0.5:
            self._refreshed = time.monotonic()
            self._open().refresh()
        return False

    def __call__(self, frame):
        if not self.enabled:
            return False
        done = "from the checkpoint" if frame.replayed else f"{frame.iterations} iterations"
        self._open().set_postfix_str(f"frame {frame.index}: {done}", refresh=False)
        self.bar.update(1)
        return False

    def _open(self):
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, unit="frame", file=sys.stderr, dynamic_ncols=True)
        return self.bar


def run_frames(frames, settings, outputs, options):
    """Every frame under the progress bar and signal handling: a first SIGINT / SIGTERM ends the frame under way
    (dropped), saves the checkpoint and writes the frames finished. Returns the result and that signal."""
    from ..video import stipple_video

    seconds, count = checkpoint_interval(options)
    progress = FrameProgress(frames.count, not options["quiet"] and sys.stderr.isatty())

    colour = settings.palette is not None

    def on_frame(frame):
        SIGNALS.begin()  # a frame to write (a resumed run's replayed ones too): a first signal lets them be written
        if colour:
            labels = [name for name, _, part in frame.inks for _ in range(part.stop - part.start)]
            outputs.add(frame.index, frame.points, frame, labels)
        else:
            outputs.add(frame.index, frame.points, frame.density)
        progress(frame)

    levels = parse_levels(options["levels"])
    identity = {
        "shape": list(frames.shape),
        "invert": bool(options["invert"]),
        "gamma": float(options["gamma"]),
        "levels": list(levels) if isinstance(levels, tuple) else levels,
        "start": options["start"],
        "step": options["step"],
    }
    pictures = (
        frames.colours()
        if colour
        else hinted(
            frames.densities(
                invert=options["invert"], gamma=options["gamma"], levels=levels, value_range=options["value_range"]
            ),
            options,
        )
    )
    progress.start(resume=options["resume"])
    with SIGNALS.deferred() as interruption:
        try:
            result = stipple_video(
                pictures,
                settings,
                on_frame=on_frame,
                stop=lambda state: progress.watch(state) or interruption.stop_requested(state),
                checkpoint=options["checkpoint"],
                resume=options["resume"],
                checkpoint_seconds=seconds,
                checkpoint_frames=count,
                identity=identity,
            )
        finally:
            progress.close()
    return result, interruption.signal


def hinted(densities, options):
    """``densities`` (``(index, density)`` per frame), with ``stipple torus``'s notes on the first frame (a faint or
    a mostly dark image, tones the pen cannot reach) said before it is stippled."""
    densities = iter(densities)
    first = next(densities, None)
    if first is None:
        return densities
    tone_hints(first[1], options)
    return itertools.chain([first], densities)


def finish(result, stopped_by, options, started):
    """The summary on stderr, and after a signal the exit status (130 / 143) and how to resume."""
    written = "outputs written" if result.frames else "no frame was finished, no output written"
    frames = f"{result.frames} frame" + ("" if result.frames == 1 else "s")
    supervise.finish(result, stopped_by, options, started, f"after {frames}; {written}", energy=False)
