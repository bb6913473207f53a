"""The fit: each setting the routine measures, with its 99% interval, from a tap's run folder.

The routine is a designed experiment (docs/calibration.md says why this method): the robot
stands still between motions and reads every sensor several times, so each quantity is a mean
or a spread of repeated, independent draws, and the fit is arithmetic on them:

- a sensor's **error**: SimMeR's percent error is ``d · (1 + 2·error·z)``, so the spread of a
  stop's reads around their mean, relative to it, has standard deviation ``2·error``; pooled
  over every stop (each stop's mean taken out), its variance has a chi-square interval;
- a sensor's **offset**: its mean at the start (a known pose) less what the maze says it
  reads there (:func:`simmer.world.expected.expected`), with a t interval;
- a straight drive's **bias** and **error** along its direction: each leg's travel is what
  the sensors facing along it saw change (their stop means before and after, over the change
  the maze predicts per inch), the sensors weighted by their precision; the travel over the
  amount commanded is ``(1 + bias)·(1 + 2·error·z)``: its mean gives the bias (t interval),
  its spread the error, after the part the sensors' own noise adds is taken out (chi-square
  interval);
- a turning drive's **bias** and **error** in rotation: the same, each turn seen by the
  gyroscope (its change over the turn, less its drift over the time between the reads),
  taking out the gyroscope's own noise (its configured error over the steps of the turn);
- the gyroscope's **drift**: its change while the robot holds still, over the hold's time
  (the tap's wall clock), a t interval over the holds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from simmer.calibrate.routine import Plan, plan
from simmer.calibrate.stats import LEVEL, Interval, mean_interval, variance_interval
from simmer.config.models import SimConfig
from simmer.errors import CalibrationError
from simmer.protocol import parse_message
from simmer.tap.folder import TapRun
from simmer.world.events import CommandEvent

HOLD_GAP = 1.0
"""Seconds between two reads with no motion between them that make them two stops (a hold)."""
ALONG = 0.1
"""How far from 1 in per inch of a leg a sensor's change in reading may be, as the maze
predicts it, for the sensor to measure the leg (it faces a flat wall along the motion)."""
STRAIGHT = 0.25
"""Inches the maze's reading of such a sensor may stray from a straight line along the leg
(its cone sweeping over a corner or an opening does not measure the leg)."""
SAMPLES = 9
"""Poses along a leg at which the maze's readings are checked."""
MIN_STOPS = 2


@dataclass
class Stop:
    """Reads where the robot stood still: each device's readings and the wall times."""

    times: list[float] = field(default_factory=list)
    readings: dict[str, list[float]] = field(default_factory=dict)

    def mean(self, device: str) -> float:
        values = self.readings.get(device, [])
        return sum(values) / len(values) if values else math.nan

    def var(self, device: str) -> float:
        values = self.readings.get(device, [])
        n = len(values)
        if n < 2:
            return math.nan
        m = sum(values) / n
        return sum((v - m) ** 2 for v in values) / (n - 1)


@dataclass(frozen=True)
class Move:
    """One accepted drive command between two stops."""

    drive: str
    amount: float
    before: Stop
    after: Stop


@dataclass(frozen=True)
class Hold:
    """Two stops with no motion between them, a hold apart."""

    before: Stop
    after: Stop


@dataclass(frozen=True)
class Segments:
    """A run cut into stops, the moves between them, and holds."""

    stops: list[Stop]
    moves: list[Move]
    holds: list[Hold]


def segment(exchanges: Sequence[CommandEvent], config: SimConfig) -> Segments:
    """Cut a run's exchanges into stops (reads with the robot still), moves (an accepted
    drive command with an amount) and holds (a still gap of :data:`HOLD_GAP` or more)."""
    kinds = {spec.id: (spec.group, spec.kind) for spec in config.devices}
    lenient = config.settings.lenient_commands
    stops: list[Stop] = []
    moves: list[Move] = []
    holds: list[Hold] = []
    current: Stop | None = None
    pending: list[tuple[str, float]] = []
    previous: Stop | None = None
    for event in exchanges:
        commands = parse_message(event.message, lenient=lenient)
        for command, reply in zip(commands, event.replies, strict=False):
            group, _kind = kinds.get(command.device, ("", ""))
            if group == "drives" and command.value != 0.0 and math.isinf(reply):
                if current is not None:
                    previous, current = current, None
                pending.append((command.device, command.value))
            elif group == "sensors" and math.isfinite(reply):
                if (
                    current is not None
                    and current.times
                    and not pending
                    and event.time - current.times[-1] >= HOLD_GAP
                ):
                    holds.append(Hold(current, new := Stop()))
                    stops.append(new)
                    current = new
                if current is None:
                    current = Stop()
                    stops.append(current)
                    if previous is not None and len(pending) == 1:
                        moves.append(Move(*pending[0], previous, current))
                    pending = []
                if not current.times or current.times[-1] != event.time:
                    current.times.append(event.time)
                current.readings.setdefault(command.device, []).append(reply)
    return Segments(stops, moves, holds)


@dataclass(frozen=True)
class Estimate:
    """One fitted setting: its dotted key, value and 95% interval, and how it was measured."""

    key: str
    value: float
    low: float
    high: float
    count: int
    how: str
    configurable: bool = True
    """False: reported only (the configuration has no setting for it)."""

    def covers(self, truth: float) -> bool:
        """Whether ``truth`` lies in the interval."""
        return self.low <= truth <= self.high


@dataclass(frozen=True)
class Calibration:
    """The fit of one run: every estimate, what the routine did, and what was left out."""

    estimates: list[Estimate]
    plan: Plan
    notes: list[str]
    segments: Segments
    ratios: dict[str, list[tuple[float, float]]]
    """Per drive, each motion's (commanded amount, measured over commanded)."""

    def value(self, key: str) -> Estimate:
        """The estimate of ``key`` (KeyError if it was not fitted)."""
        for estimate in self.estimates:
            if estimate.key == key:
                return estimate
        raise KeyError(key)


def _axis(unit: tuple[float, float]) -> tuple[str, float]:
    """The robot axis a drive's direction lies along, and its sign."""
    if abs(unit[1]) >= abs(unit[0]):
        return "y", math.copysign(1.0, unit[1])
    return "x", math.copysign(1.0, unit[0])


def _scale_fit(
    key: str, axis: str, sign: float, samples: list[tuple[float, float, float]], how: str
) -> list[Estimate]:
    """Bias and error of a drive from (amount, ratio, noise variance of the ratio) samples."""
    ratios = [r for _, r, _ in samples]
    n = len(ratios)
    mean, low, high = mean_interval(ratios)
    estimates = [
        Estimate(
            f"{key}.bias.{axis}",
            sign * (mean - 1.0),
            sign * (low - 1.0) if sign > 0 else sign * (high - 1.0),
            sign * (high - 1.0) if sign > 0 else sign * (low - 1.0),
            n,
            f"mean of {n} {how} over the amount commanded, less 1",
        )
    ]
    ss = sum((r - mean) ** 2 for r in ratios)
    noise = sum(v for _, _, v in samples) / n
    _var, var_low, var_high = variance_interval(ss, n - 1)

    def error(variance: float) -> float:
        return math.sqrt(max(variance - noise, 0.0)) / (2.0 * mean)

    estimates.append(
        Estimate(
            f"{key}.error.{axis}",
            error(ss / (n - 1)),
            error(var_low),
            error(var_high),
            n,
            f"spread of the {n} {how} over the amount commanded (sd = 2·error·(1 + bias)), "
            "the measurement's own noise taken out",
        )
    )
    return estimates


def calibrate(run: TapRun, config: SimConfig | None = None) -> Calibration:
    """Fit a run of the routine (``config``: the robot's configuration, default the one the
    tap recorded). CalibrationError if the run is not the routine's."""
    from simmer.world.expected import expected
    from simmer.world.simulation import Simulation

    config = config if config is not None else run.config
    routine = plan(config)
    parts = segment(run.exchanges, config)
    where = run.folder
    if len(parts.stops) < MIN_STOPS:
        raise CalibrationError(
            f"{where}: {len(parts.stops)} stop(s) with sensor reads; the calibration routine "
            "makes dozens (simmer calibrate routine writes it; run it through simmer tap)"
        )
    sim = Simulation(config, seed=0)
    estimates: list[Estimate] = []
    notes: list[str] = []
    params = {spec.id: spec.params for spec in config.devices}
    # sensors: error from every stop's spread, offset at the start
    start = parts.stops[0]
    at_start = expected(sim, [routine.start], list(routine.sensors))[0]
    for column, sensor in enumerate(routine.sensors):
        low_range = float(getattr(params[sensor], "min_range", 0.0))
        high_range = float(getattr(params[sensor], "max_range", math.inf))
        ss, df, count = 0.0, 0, 0
        for stop in parts.stops:
            values = stop.readings.get(sensor, [])
            if len(values) < 2 or not all(low_range < v < high_range for v in values):
                continue
            m = sum(values) / len(values)
            ss += sum((v / m - 1.0) ** 2 for v in values)
            df += len(values) - 1
            count += len(values)
        if df:
            var, low, high = variance_interval(ss, df)
            estimates.append(
                Estimate(
                    f"sensors.{sensor}.error",
                    math.sqrt(var) / 2,
                    math.sqrt(low) / 2,
                    math.sqrt(high) / 2,
                    count,
                    f"spread of {count} reads at {len(parts.stops)} stops (sd = 2·error)",
                )
            )
        values = start.readings.get(sensor, [])
        if len(values) >= 2:
            mean, low, high = mean_interval(values)
            truth = float(at_start[column])
            estimates.append(
                Estimate(
                    f"sensors.{sensor}.offset",
                    mean - truth,
                    low - truth,
                    high - truth,
                    len(values),
                    f"mean of {len(values)} reads at the start less the maze's {truth:.2f} in",
                    configurable=False,
                )
            )
    ratios: dict[str, list[tuple[float, float]]] = {}
    # the straight drive: travel seen by the sensors facing along it
    drive = sim.robot.drives[routine.drive]
    axis, sign = _axis(drive.unit)
    x0, y0, h0 = routine.start
    unit = drive.unit
    rad = math.radians(h0)
    dx = unit[0] * math.cos(rad) - unit[1] * math.sin(rad)
    dy = unit[0] * math.sin(rad) + unit[1] * math.cos(rad)
    along = np.linspace(0.0, routine.leg, SAMPLES)
    poses = [(x0 + dx * a, y0 + dy * a, h0) for a in along]
    maze = expected(sim, poses, list(routine.sensors))
    per_inch: dict[str, float] = {}
    for i, sensor in enumerate(routine.sensors):
        slope, intercept = np.polyfit(along, maze[:, i], 1)
        stray = float(np.max(np.abs(maze[:, i] - (slope * along + intercept))))
        if abs(abs(slope) - 1.0) <= ALONG and stray <= STRAIGHT:
            per_inch[sensor] = float(slope)
    facing = list(per_inch)
    legs: list[tuple[float, float, float]] = []
    for move in parts.moves:
        if move.drive != routine.drive or not facing or abs(move.amount) < routine.leg / 2:
            continue  # a short move (back to the start) says little of the drive's scale
        weighted, weights = 0.0, 0.0
        for sensor in facing:
            change = move.after.mean(sensor) - move.before.mean(sensor)
            n_b = len(move.before.readings.get(sensor, []))
            n_a = len(move.after.readings.get(sensor, []))
            if not math.isfinite(change) or n_b < 2 or n_a < 2:
                continue
            k = per_inch[sensor]
            noise = (move.before.var(sensor) / n_b + move.after.var(sensor) / n_a) / k**2
            weight = 1.0 / max(noise, 1e-12)  # the sensors' travels, by their precision
            weighted += weight * change / k
            weights += weight
        if weights:
            ratio = weighted / weights / move.amount
            legs.append((move.amount, ratio, 1.0 / weights / move.amount**2))
    if len(legs) >= 3:
        ratios[routine.drive] = [(a, r) for a, r, _ in legs]
        estimates += _scale_fit(
            f"drives.{routine.drive}",
            axis,
            sign,
            legs,
            f"legs' travel (seen by {', '.join(facing)})",
        )
    else:
        notes.append(
            f"{routine.drive}: {len(legs)} legs measured (3 or more needed): not fitted; are "
            "the sensors facing along the legs seeing a wall?"
        )
    # the gyroscope's drift, then the turns it saw
    gyro = routine.gyros[0] if routine.gyros else None
    drift = 0.0
    if gyro is not None:
        rates = []
        for hold in parts.holds:
            before, after = hold.before.readings.get(gyro), hold.after.readings.get(gyro)
            if not before or not after:
                continue
            span = hold.after.times[0] - hold.before.times[-1]
            change = (after[0] - before[-1] + 180.0) % 360.0 - 180.0
            rates.append(change / span)
        if len(rates) >= 2:
            drift, low, high = mean_interval(rates)
            estimates.append(
                Estimate(
                    f"sensors.{gyro}.bias",
                    drift,
                    low,
                    high,
                    len(rates),
                    f"change over {len(rates)} holds of the robot, over their wall time",
                )
            )
        else:
            notes.append(f"{gyro}: fewer than 2 holds: its drift is not fitted")
    if routine.turn is not None and gyro is not None:
        turn = sim.robot.drives[routine.turn]
        gyro_error = float(getattr(params[gyro], "error", 0.0))
        per_step = turn.speed / config.settings.frame_rate
        turns: list[tuple[float, float, float]] = []
        for move in parts.moves:
            before, after = move.before.readings.get(gyro), move.after.readings.get(gyro)
            if move.drive != routine.turn or not before or not after:
                continue
            span = move.after.times[0] - move.before.times[-1]
            change = (after[0] - before[-1] - drift * span + 180.0) % 360.0 - 180.0
            noise = 4 * gyro_error**2 * abs(move.amount) * per_step / move.amount**2
            turns.append((move.amount, change / move.amount, noise))
        if len(turns) >= 3:
            ratios[routine.turn] = [(a, r) for a, r, _ in turns]
            estimates += _scale_fit(
                f"drives.{routine.turn}", "rotation", 1.0, turns, f"turns (seen by {gyro})"
            )
    elif routine.turn is not None:
        notes.append(
            f"{routine.turn}: the robot has no gyroscope to see its turns: not fitted (the "
            "ultrasonic sensors' 15-degree cones cannot see a few degrees)"
        )
    notes.append(
        f"every interval is {LEVEL:.0%}; not fitted by this routine: a straight drive's "
        "sideways drift and turn per inch, a sensor's mount angle, the gyroscope's own error"
    )
    return Calibration(estimates, routine, notes, parts, ratios)


def fragment(calibration: Calibration, source: str) -> str:
    """The fitted values as a TOML fragment of dotted keys (pasted into the robot's
    configuration, or given to ``simmer compare --fitted``): each value with its interval."""
    lines = [
        f"# Fitted by simmer calibrate from {source}: each value's {LEVEL:.0%} interval beside",
        "# it. Paste into the robot's configuration (or: simmer compare RUN --config CONFIG",
        "# --fitted THIS_FILE). docs/calibration.md says how each was measured.",
    ]
    tables: dict[str, list[Estimate]] = {}
    for estimate in calibration.estimates:
        group, device, *_ = estimate.key.split(".")
        tables.setdefault(f"{group}.{device}", []).append(estimate)
    for table, estimates in tables.items():
        lines += ["", f"[{table}]"]
        for estimate in estimates:
            name = estimate.key.split(".", 2)[2]
            interval = f"[{estimate.low:.4g}, {estimate.high:.4g}]"
            text = f"{name} = {_value(estimate)}  # {LEVEL:.0%}: {interval}, n = {estimate.count}"
            if not estimate.configurable:
                text = (
                    f"# {name} = {estimate.value:.4g} in {interval}: no setting; if the interval "
                    "leaves out 0, move the sensor's position by it along its direction"
                )
            lines.append(text)
    return "\n".join(lines) + "\n"


def _value(estimate: Estimate) -> str:
    value = max(estimate.value, 0.0) if ".error" in estimate.key else estimate.value
    return f"{value:.5g}" if "e" not in f"{value:.5g}" else f"{value:.6f}"


def setting(key: str, value: float) -> float:
    """``value`` as the setting ``key`` takes it: an error is never below 0."""
    return max(value, 0.0) if ".error" in key else value


def fitted_overrides(calibration: Calibration) -> dict[str, float]:
    """The fitted values as dotted overrides of a configuration."""
    return {e.key: setting(e.key, e.value) for e in calibration.estimates if e.configurable}


def intervals(calibration: Calibration) -> dict[str, Interval]:
    """Each fitted setting with its interval (those with a setting and finite ends): what
    ``simmer compare`` draws each seed's settings from."""
    return {
        e.key: Interval(setting(e.key, e.value), e.low, e.high)
        for e in calibration.estimates
        if e.configurable and math.isfinite(e.low) and math.isfinite(e.high)
    }


INTERVALS_SUFFIX = ".intervals.toml"
"""The side file beside a fitted fragment (``fitted.toml``: ``fitted.intervals.toml``)."""


def intervals_path(fitted: Path) -> Path:
    """Where the intervals of the fitted fragment ``fitted`` are kept."""
    return fitted.with_name(fitted.stem + INTERVALS_SUFFIX)


def intervals_document(calibration: Calibration, source: str) -> str:
    """The fitted values' intervals as TOML (``simmer compare --fitted`` reads them beside the
    fragment): a table per dotted key with its value, ends, level and count. Not a
    configuration: the fragment is; this says how sure the fit is of it."""
    lines = [
        f"# The {LEVEL:.0%} intervals of the fitted values beside this file, fitted by simmer",
        f"# calibrate from {source}. simmer compare --fitted reads them to draw each seed's",
        "# settings from them (docs/calibration.md). Not a configuration: do not paste it.",
    ]
    for key, interval in intervals(calibration).items():
        count = calibration.value(key).count
        lines += [
            "",
            f'["{key}"]',
            f"value = {interval.value!r}",
            f"low = {interval.low!r}",
            f"high = {interval.high!r}",
            f"level = {interval.level!r}",
            f"count = {count}",
        ]
    return "\n".join(lines) + "\n"
