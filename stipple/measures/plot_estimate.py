"""The plot before the plot: pen-down length, pen-up travel, pen lifts and time of an SVG on a pen plotter.

The model, per layer (one pen): the pen starts at the page's origin (home), draws the layer's strokes in
document order, lifting after each, and returns home (where the pen is changed for the next layer). Pen-down
moves run at ``speed``, pen-up moves at ``travel_speed``, every stroke costs ``lift`` seconds (lowering and
raising the pen). With ``acceleration`` every stroke and every pen-up move is one move from rest to rest at
that constant acceleration and deceleration, capped at its speed (corners inside a stroke are taken without
slowing: a lower bound for sharp corners); without it moves start and stop at full speed.

``pen_up`` is the travel between consecutive strokes (what ``vpype stat`` calls the pen-up length); ``home`` the
travel from the origin to the first stroke and from the last stroke back.
"""

from dataclasses import asdict, dataclass

import numpy as np

from ..errors import StippleError

# Roughly an AxiDraw V3 at its default settings (25 % and 75 % of its top speed, a servo lift of ~0.15 s each way).
DEFAULT_SPEED = 55.0
DEFAULT_TRAVEL_SPEED = 165.0
DEFAULT_LIFT = 0.3
# Bounds a plotter can have (--speed 1e-300 printed a time of 300 digits).
MIN_SPEED, MAX_SPEED, MAX_LIFT, MAX_ACCELERATION = 0.01, 1e5, 60.0, 1e7


@dataclass(frozen=True)
class PlotterSettings:
    """Speeds in mm/s, ``lift`` in seconds per stroke, ``acceleration`` in mm/s² (None: instantaneous)."""

    speed: float = DEFAULT_SPEED
    travel_speed: float = DEFAULT_TRAVEL_SPEED
    lift: float = DEFAULT_LIFT
    acceleration: float | None = None

    def __post_init__(self):
        for name, value in (("speed", self.speed), ("travel-speed", self.travel_speed)):
            if not (np.isfinite(value) and MIN_SPEED <= value <= MAX_SPEED):
                raise StippleError(f"--{name} must be a speed in [{MIN_SPEED:g}, {MAX_SPEED:g}] mm/s, not {value!r}")
        if not (np.isfinite(self.lift) and 0 <= self.lift <= MAX_LIFT):
            raise StippleError(f"--lift must be a time in [0, {MAX_LIFT:g}] s, not {self.lift!r}")
        acceleration = self.acceleration
        if acceleration is not None and not (
            np.isfinite(acceleration) and MIN_SPEED <= acceleration <= MAX_ACCELERATION
        ):
            raise StippleError(
                f"--acceleration must be in [{MIN_SPEED:g}, {MAX_ACCELERATION:g}] mm/s², not {acceleration!r}"
            )


@dataclass
class LayerEstimate:
    """One pen's plot (or the total): lengths in mm, times in seconds."""

    name: str
    paths: int
    segments: int
    pen_down: float
    pen_up: float
    home: float
    lifts: int
    draw_time: float
    travel_time: float
    lift_time: float

    @property
    def time(self):
        return self.draw_time + self.travel_time + self.lift_time


@dataclass
class PlotEstimate:
    """Per-layer estimates, their total and the settings used."""

    layers: list
    total: LayerEstimate
    settings: PlotterSettings

    def as_dict(self):
        """Plain numbers for JSON: every layer and the total with its ``time``, and the settings."""

        def entry(estimate):
            return {**asdict(estimate), "time": estimate.time}

        return {
            "layers": [entry(layer) for layer in self.layers],
            "total": entry(self.total),
            "settings": asdict(self.settings),
        }


def move_times(lengths, speed, acceleration=None):
    """Seconds of straight moves of ``lengths`` from rest to rest, at most ``speed``, accelerating and
    decelerating at ``acceleration`` (trapezoidal profile; triangular when too short to reach ``speed``)."""
    lengths = np.asarray(lengths, dtype=np.float64)
    if acceleration is None:
        return lengths / speed
    ramp = speed**2 / acceleration  # the distance to reach full speed and stop again
    return np.where(lengths >= ramp, lengths / speed + speed / acceleration, 2 * np.sqrt(lengths / acceleration))


def layer_estimate(name, paths, settings):
    """The ``LayerEstimate`` of strokes ``paths`` (complex vertex arrays in mm, in plot order)."""
    if not paths:
        return LayerEstimate(name, 0, 0, 0.0, 0.0, 0.0, 0, 0.0, 0.0, 0.0)
    lengths = np.array([np.abs(np.diff(path)).sum() for path in paths])
    starts = np.array([path[0] for path in paths])
    ends = np.array([path[-1] for path in paths])
    hops = np.abs(starts[1:] - ends[:-1])
    home = np.array([abs(starts[0]), abs(ends[-1])])
    travel = move_times(hops, settings.travel_speed, settings.acceleration).sum()
    travel += move_times(home, settings.travel_speed, settings.acceleration).sum()
    return LayerEstimate(
        name=name,
        paths=len(paths),
        segments=int(sum(len(path) - 1 for path in paths)),
        pen_down=float(lengths.sum()),
        pen_up=float(hops.sum()),
        home=float(home.sum()),
        lifts=len(paths),
        draw_time=float(move_times(lengths, settings.speed, settings.acceleration).sum()),
        travel_time=float(travel),
        lift_time=len(paths) * settings.lift,
    )


def plot_estimate(layers, settings=None):
    """The ``PlotEstimate`` of ``stipple.io.plot_svg.PenLayer``s (each plotted from home and back, in turn)."""
    settings = PlotterSettings() if settings is None else settings
    estimates = [layer_estimate(layer.name, layer.paths, settings) for layer in layers]
    sums = {
        key: sum(getattr(estimate, key) for estimate in estimates)
        for key in ("paths", "segments", "pen_down", "pen_up", "home", "lifts", "draw_time", "travel_time", "lift_time")
    }
    return PlotEstimate(estimates, LayerEstimate("total", **sums), settings)


def clock(seconds):
    """``1h02m03s`` / ``2m03s`` / ``4.5s``."""
    seconds = float(seconds)
    if seconds < 60:
        return f"{seconds:.1f}s"
    minutes, rest = divmod(int(round(seconds)), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}h{minutes:02d}m{rest:02d}s" if hours else f"{minutes}m{rest:02d}s"


def format_estimate(estimate):
    """The estimate as a text table: one row per layer and the total."""
    settings = estimate.settings
    accel = "no acceleration" if settings.acceleration is None else f"acceleration {settings.acceleration:g} mm/s²"
    lines = [
        f"plot estimate: pen down {settings.speed:g} mm/s, pen up {settings.travel_speed:g} mm/s, "
        f"{settings.lift:g} s per lift, {accel}",
        f"{'layer':<20} {'paths':>8} {'pen-down mm':>12} {'pen-up mm':>11} {'home mm':>9} {'lifts':>8} {'time':>10}",
    ]
    rows = estimate.layers + ([estimate.total] if len(estimate.layers) != 1 else [])
    for row in rows:
        lines.append(
            f"{row.name[:20]:<20} {row.paths:>8} {row.pen_down:>12.1f} {row.pen_up:>11.1f} {row.home:>9.1f} "
            f"{row.lifts:>8} {clock(row.time):>10}"
        )
    total = estimate.total
    lines.append(
        f"time {clock(total.time)}: drawing {clock(total.draw_time)}, travel {clock(total.travel_time)}, "
        f"lifts {clock(total.lift_time)}"
    )
    return "\n".join(lines)
