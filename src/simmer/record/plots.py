"""Plots of a recorded run: the path over the maze (``path.png``) and the sensor readings
against time (``sensors.png``), in world inches with +y down the page as in the window.

What is read from a run folder (through :mod:`simmer.record.reader`, for the events and trace):

- ``trace.csv``: a header row, then one row per trace sample. Columns ``time`` (simulated
  seconds), ``x``, ``y`` (inches) and ``heading`` (degrees) are required; ``step`` and
  ``collisions`` are known and not plotted; every other column whose cells are numbers (or blank
  before a sensor's first reading) is a sensor, plotted under its header (its id, e.g. ``u0``).
  A last line cut before its newline (a killed run's), rows that do not parse and rows whose
  pose is beyond :data:`MAX_POSE_VALUE` are skipped. A reset puts the simulated clock back to
  0: where ``time`` goes backwards a new part of the run begins.
- ``events.jsonl`` (optional): one JSON object per line with ``type``, ``time`` and more.
  ``command`` events (``message``, ``replies``: numbers, or the strings "nan", "inf", "-inf")
  are numbered from 1 along the path; ``collision`` events are marked at their ``pose``
  ``[x, y, heading]`` (else where the trace was at that time); ``reached`` is marked; ``reset``
  starts the next part of the run. Other types, unknown keys and lines that do not parse are
  ignored.
- ``manifest.json``: ``config.settings`` (the configuration's settings, as
  :class:`~simmer.config.models.Settings` dumps them; unknown keys are ignored) draws the maze,
  floor, start and block exactly as the simulator does. Optional: ``seed`` and
  ``config.source`` are shown in the title; ``config.devices`` (a list of ``{"id", "kind"}``)
  puts sensors of one kind in one panel with its unit (without it: ids starting with the same
  letters, ``u0`` and ``u1``, share a panel).

Matplotlib (Agg backend, no pyplot) is imported only when a plot is drawn.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from pydantic import ValidationError

from simmer.colors import START_COLOR as START_RGB
from simmer.colors import TRAIL_COLOR, Color
from simmer.config.maze import Maze
from simmer.config.models import Settings
from simmer.config.zones import Zones
from simmer.errors import PlotError, RunFolderError, UnsafeOutput
from simmer.geometry import FloatArray, Pose
from simmer.record.page import draw_items, rgb
from simmer.record.reader import (
    EVENTS,
    SCANS,
    TRACE,
    RecordedScan,
    event_objects,
    read_scans,
    read_trace,
)
from simmer.record.safefile import check_target, replacing, write_text
from simmer.scene import (
    Look,
    Walls,
    block_items,
    maze_items,
    placed_block,
    placed_robot,
    put_down_block,
    robot_items,
)
from simmer.untrusted import drawable, read_at_most
from simmer.world.localization import (
    HEADING_TOLERANCE,
    MAX_ERRORS,
    POSITION_TOLERANCE,
    errors,
    localized_at,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.projections.polar import PolarAxes

log = logging.getLogger("simmer.plot")

MANIFEST_FILE = "manifest.json"
REPORT_FILE = "report.md"
PATH_IMAGE = "path.png"
SENSORS_IMAGE = "sensors.png"
SCANS_IMAGE = "scans.png"
"""Every scan point of a run with a LiDAR, drawn by every ``simmer plot``."""
SCAN_IMAGE = "scan.png"
"""One scan, drawn by ``simmer plot --scan-at T``."""
SCANS_WORDS = (SCANS_IMAGE, "Every LiDAR scan point over the maze")
SCAN_WORDS = (SCAN_IMAGE, "One LiDAR scan, over the maze and as read")
SCAN_RGB: Color = (220, 0, 220)
SCAN_COLOR = "#" + bytes(SCAN_RGB).hex()
"""The scan points' colour: the window's (the lidar kind's ``point_color``)."""

COL_TIME, COL_X, COL_Y, COL_HEADING = "time", "x", "y", "heading"
TRACE_REQUIRED = (COL_TIME, COL_X, COL_Y, COL_HEADING)
TRACE_NOT_SENSORS = frozenset({*TRACE_REQUIRED, "step", "collisions"})
"""Trace columns that are not sensor readings."""

EV_TYPE, EV_TIME, EV_MESSAGE, EV_REPLIES, EV_POSE = "type", "time", "message", "replies", "pose"
EV_COMMAND, EV_COLLISION, EV_RESET, EV_REACHED = "command", "collision", "reset", "reached"
EV_ESTIMATE, EV_TRUTH = "estimate", "truth"
MANIFEST_CONFIG, MANIFEST_SETTINGS, MANIFEST_SEED = "config", "settings", "seed"
MANIFEST_SOURCE, MANIFEST_DEVICES, DEVICE_ID, DEVICE_KIND = "source", "devices", "id", "kind"
SENSOR_UNITS = {
    "ultrasonic": "distance (in)",
    "infrared": "floor (1 white, 0 black)",
    "compass": "heading (°)",
    "gyroscope": "angle turned (°)",
    "tof": "distance (in, or mm)",
    "imu": "yaw rate (°/s)",
    "imu-1": "acceleration (in/s²)",
    "imu-2": "acceleration (in/s²)",
    "encoder": "wheel counts",
}
"""What the built-in sensor kinds read, for the y axis of their panel."""
LOCALIZATION_IMAGE = "localization.png"
LOCALIZATION_WORDS = (LOCALIZATION_IMAGE, "The program's estimate against the truth")
IMAGES = ((PATH_IMAGE, "The robot's true path"), (SENSORS_IMAGE, "Sensor readings against time"))
"""The images :func:`plot_run` draws, with the words report.md shows for each."""

PATH_COLOR = "#" + bytes(TRAIL_COLOR).hex()
COMMAND_COLOR = "#1f3b73"
NAN_COLOR = "#d7191c"
COLLISION_COLOR = "#ff00c8"
START_COLOR = "#" + bytes(START_RGB).hex()
DPI = 110
PAGE_INCHES = 12.0
"""Inches of the page the maze's longest side takes on path.png."""
LABEL_POINTS = 7
LABEL_SPACING = 3.0
"""Inches at least between command labels on the path: commands sent closer share one."""
MAX_PATH_LABELS = 30
"""About as many command labels at most along the path (more are spaced further apart)."""
MAX_TIME_LABELS = 40
"""Command labels at most across the sensor plot's width."""
MAX_SHOWN_CHARS = 60
"""Characters of the configuration's name the title shows (then "...")."""
MAX_REPORT_BYTES = 1_000_000
"""Largest ``report.md`` (of some other origin) that ``simmer plot`` reads to link the plots
from; SimMeR's own are a few kilobytes."""
MAX_POSE_VALUE = 1e9
"""A trace row whose time, x, y or heading is larger (or not finite) is not a recorded pose and
is left out (a command's value is at most 1e9 too): an edited 1e300 printed a path length of
300 digits across the title."""


@dataclass(frozen=True)
class Command:
    """One command event: its number (from 1), when, in which part of the run, and replies."""

    number: int
    time: float
    part: int
    message: str
    replies: tuple[float, ...]

    @property
    def nan(self) -> bool:
        """Whether any reply was NaN (the command failed)."""
        return any(math.isnan(r) for r in self.replies)


@dataclass(frozen=True)
class Mark:
    """A collision or the block reached: when, in which part of the run, and where if known."""

    time: float
    part: int
    pose: tuple[float, float] | None = None


@dataclass
class Trace:
    """The trace columns as arrays; ``part`` counts resets (the clock went back)."""

    time: FloatArray
    x: FloatArray
    y: FloatArray
    heading: FloatArray
    part: np.ndarray[Any, np.dtype[np.int64]]
    sensors: dict[str, FloatArray]

    @property
    def parts(self) -> int:
        """Parts of the run (one more than the resets seen in the trace)."""
        return int(self.part[-1]) + 1

    def positions(self, marks: Sequence[Command | Mark]) -> FloatArray:
        """Where the robot was at each command or mark, (N, 2), interpolated between samples
        of its part of the run."""
        times = np.array([m.time for m in marks], dtype=np.float64)
        parts = np.minimum([m.part for m in marks], self.parts - 1)
        result = np.zeros((len(marks), 2))
        for p in np.unique(parts).tolist():
            rows, chosen = self.part == p, parts == p
            result[chosen, 0] = np.interp(times[chosen], self.time[rows], self.x[rows])
            result[chosen, 1] = np.interp(times[chosen], self.time[rows], self.y[rows])
        return result

    def offsets(self) -> FloatArray:
        """Seconds to add to each part's times to put the parts one after the other."""
        ends = [float(self.time[self.part == p][-1]) for p in range(self.parts)]
        return np.concatenate(([0.0], np.cumsum(ends[:-1])))

    def run_time(self) -> FloatArray:
        """Each sample's time with the parts one after the other (for plotting against)."""
        result: FloatArray = self.time + self.offsets()[self.part]
        return result

    def run_times(self, commands: Sequence[Command]) -> FloatArray:
        """The times of commands with the parts of the run one after the other."""
        offsets = self.offsets()
        return np.array([c.time + offsets[min(c.part, self.parts - 1)] for c in commands])

    def length(self) -> float:
        """Inches driven (jumps between parts left out)."""
        same = self.part[1:] == self.part[:-1]
        return float(np.hypot(np.diff(self.x), np.diff(self.y))[same].sum())


@dataclass
class RecordedRun:
    """What the plots need from a run folder."""

    folder: Path
    settings: Settings
    seed: int | None
    trace: Trace
    source: str = ""
    """The configuration file the run used (its name is shown), "" if unknown."""
    kinds: dict[str, str] = field(default_factory=dict)
    """Device kind of each device id the manifest lists."""
    commands: list[Command] = field(default_factory=list)
    collisions: list[Mark] = field(default_factory=list)
    reached: list[Mark] = field(default_factory=list)
    scenario: RecordedScenario | None = None
    """A project run's start, block and target (the manifest's ``scenario``), if readable."""
    estimates: list[Estimate] = field(default_factory=list)
    """The program's reported poses (``robot.report_pose`` or shown), at most
    :data:`~simmer.world.localization.MAX_ERRORS`."""
    handled: Handled | None = None
    """A project run's pickup and delivery (from ``report.json``), if it picked the block up."""


@dataclass(frozen=True)
class Handled:
    """When a project run picked its block up, and when and in which zone it put it down
    (``delivered`` True: its target; None: it never did)."""

    picked_up: float
    put_down: float | None = None
    zone: str | None = None
    delivered: bool = False


@dataclass(frozen=True)
class Estimate:
    """A reported pose's error: inches and degrees off the truth, when."""

    time: float
    part: int
    position: float
    heading: float


@dataclass(frozen=True)
class RecordedScenario:
    """Where a project run started, where its block lay, and its target zone."""

    start: tuple[float, float, float]
    block: tuple[float, float]
    target: str | None


@dataclass(frozen=True)
class PixelMap:
    """World inches to pixels of a saved image: column from the left, row from the top."""

    x0: float
    x_scale: float
    y0: float
    y_scale: float

    def pixel(self, x: float, y: float) -> tuple[float, float]:
        """The pixel (column, row) of world point (x, y)."""
        return self.x0 + self.x_scale * x, self.y0 + self.y_scale * y


# ----------------------------------------------------------------------------- reading


def read_run(folder: str | Path) -> RecordedRun:
    """Read a run folder (see the module docstring); :class:`PlotError` if it cannot be."""
    folder = Path(folder)
    if not folder.is_dir():
        raise PlotError(f"{folder} is not a folder; give a run folder (simmer run --record DIR)")
    if not (folder / TRACE).is_file():
        raise PlotError(
            f"no {TRACE} in {folder}: not a run folder (record one with simmer run --record)"
        )
    try:
        trace = _read_trace(folder / TRACE)
        run = _read_manifest(folder / MANIFEST_FILE, folder, trace)
        if (folder / EVENTS).is_file():
            _read_events(folder / EVENTS, run)
        run.handled = _handled(folder)
    except RunFolderError as exc:  # the reader's one line, naming the file
        raise PlotError(str(exc)) from None
    return run


def _read_trace(path: Path) -> Trace:
    """The trace's columns; a new part wherever the clock goes back (a reset)."""
    table = read_trace(path)
    header, rows = [name.strip() for name in table.header], table.rows
    missing = [name for name in TRACE_REQUIRED if name not in header]
    if missing:
        raise PlotError(f"{path} has no column {', '.join(missing)} (its header: {header})")
    index = {name: i for i, name in enumerate(header)}
    candidates = [name for name in header if name and name not in TRACE_NOT_SENSORS]
    required, values = [index[name] for name in TRACE_REQUIRED], []
    for row in rows:
        if len(row) != len(header):
            continue
        try:
            pose = [float(row[i]) for i in required]
        except ValueError:
            continue
        if all(abs(v) <= MAX_POSE_VALUE for v in pose):  # False for NaN too
            values.append((pose, row))
    if not values:
        said = cut_short_of(path.parent, None) or "the run recorded nothing"
        raise PlotError(f"{path} has no rows of data: {said}")
    poses = np.array([pose for pose, _ in values], dtype=np.float64)
    sensors = {}
    for name in candidates:
        column = [_number(row[index[name]]) for _, row in values]
        if all(v is not None for v in column):
            sensors[name] = np.array(column, dtype=np.float64)
    time = poses[:, 0]
    part = np.concatenate(([0], np.cumsum(np.diff(time) < 0))).astype(np.int64)
    return Trace(time, poses[:, 1], poses[:, 2], poses[:, 3], part, sensors)


def _number(cell: str) -> float | None:
    """A cell as a number (blank: NaN, before a sensor's first reading); None if not one."""
    if not cell.strip():
        return math.nan
    try:
        return float(cell)
    except ValueError:
        return None


def _read_manifest(path: Path, folder: Path, trace: Trace) -> RecordedRun:
    """The run a manifest describes, with this trace (no events yet)."""
    from simmer.record.runfolder import read_manifest, recorded_source

    if not path.is_file():
        raise PlotError(f"no {MANIFEST_FILE} in {path.parent}: the maze to draw is unknown")
    try:
        manifest = read_manifest(path.parent)
    except OSError as exc:
        raise PlotError(f"cannot read {path}: {exc}") from None
    except ValueError as exc:
        raise PlotError(str(exc)) from None
    config = manifest.get(MANIFEST_CONFIG)
    data = config.get(MANIFEST_SETTINGS) if isinstance(config, dict) else None
    if not isinstance(config, dict) or not isinstance(data, dict):
        raise PlotError(f"{path} has no {MANIFEST_CONFIG}.{MANIFEST_SETTINGS}: the maze is unknown")
    settings = _settings(path, data)
    seed = manifest.get(MANIFEST_SEED)
    source = config.get(MANIFEST_SOURCE)
    devices = config.get(MANIFEST_DEVICES)
    kinds = {
        device[DEVICE_ID]: device[DEVICE_KIND]
        for device in (devices if isinstance(devices, list) else [])
        if isinstance(device, dict)
        and isinstance(device.get(DEVICE_ID), str)
        and isinstance(device.get(DEVICE_KIND), str)
    }
    return RecordedRun(
        folder,
        settings,
        seed if isinstance(seed, int) and not isinstance(seed, bool) else None,
        trace,
        recorded_source(source) if isinstance(source, str) else "",
        kinds,
        scenario=_scenario(manifest.get("scenario")),
    )


def _scenario(value: Any) -> RecordedScenario | None:
    """A manifest's ``scenario``, or None if it is missing or not numbers where they belong."""
    if not isinstance(value, dict):
        return None
    start, block, target = value.get("start"), value.get("block"), value.get("target")
    numbers = [*start, *block] if isinstance(start, list) and isinstance(block, list) else []
    if len(numbers) != 5 or not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in numbers
    ):
        return None
    x, y, heading, bx, by = (float(v) for v in numbers)
    return RecordedScenario((x, y, heading), (bx, by), target if isinstance(target, str) else None)


def _handled(folder: Path) -> Handled | None:
    """A project run's pickup and delivery as its ``report.json`` has them; None if it has
    none (no report, another kind of run, or no pickup) or cannot be read: the plots are drawn
    without the marks, and writing report.md says in one line what is wrong with it."""
    from simmer.record.runfolder import REPORT_JSON, read_json

    if not (folder / REPORT_JSON).is_file():
        return None
    try:
        outcome = read_json(folder / REPORT_JSON).get("outcome")
    except ValueError:
        return None
    if not isinstance(outcome, dict):
        return None
    picked = _float(outcome.get("picked_up_at"))
    if not math.isfinite(picked):
        return None
    delivered = _float(outcome.get("delivered_at"))
    if math.isfinite(delivered):
        zone = outcome.get("target")
        return Handled(picked, delivered, zone if isinstance(zone, str) else None, True)
    wrong = _float(outcome.get("wrong_zone_at"))
    zone = outcome.get("wrong_zone")
    if math.isfinite(wrong) and isinstance(zone, str):
        return Handled(picked, wrong, zone)
    return Handled(picked)


def _settings(path: Path, data: dict[str, Any]) -> Settings:
    """A manifest's settings, with the maze checked as a run's is (a 2000 x 2000 ``walls``
    would take gigabytes to draw); PlotError naming the first problem."""
    from simmer.config.validate import maze_issues, oversize_walls

    known = {key: value for key, value in data.items() if key in Settings.model_fields}
    issue = oversize_walls(known.get("walls"))
    if issue is None:
        try:
            settings = Settings.model_validate(known)
        except ValidationError as exc:
            first = exc.errors()[0]
            where = ".".join(str(part) for part in first["loc"])
            raise PlotError(f"{path}: setting {where}: {first['msg']}") from None
        issue = next(iter(maze_issues(settings)), None)
        if issue is None:
            return settings
    raise PlotError(f"{path}: the recorded maze is not valid: {issue.key}: {issue.message}")


def _read_events(path: Path, run: RecordedRun) -> None:
    """Add the commands, collisions and block reached that ``events.jsonl`` holds to ``run``;
    PlotError for an event at a time no run of the limit reaches (:data:`MAX_RUN_SECONDS`
    past the trace's end: a label there overflows the drawing); RunFolderError if the file
    cannot be read (:func:`read_run` says it as a PlotError)."""
    from simmer.record.runfolder import MAX_RUN_SECONDS

    latest = float(np.max(run.trace.time)) + MAX_RUN_SECONDS
    part = 0
    for number, event in event_objects(path):
        kind, time = event.get(EV_TYPE), _float(event.get(EV_TIME))
        if kind == EV_RESET:
            part += 1
        elif not math.isfinite(time):
            continue
        elif not 0 <= time <= latest:
            raise PlotError(
                f"{path} line {number}: time {time:g} s is outside the run (its trace ends at "
                f"{latest - MAX_RUN_SECONDS:g} s): not a recorded event"
            )
        elif kind == EV_COMMAND:
            replies = event.get(EV_REPLIES)
            values = tuple(_float(r) for r in replies) if isinstance(replies, list) else ()
            message = str(event.get(EV_MESSAGE, ""))
            run.commands.append(Command(len(run.commands) + 1, time, part, message, values))
        elif kind == EV_COLLISION:
            run.collisions.append(Mark(time, part, _position(event.get(EV_POSE))))
        elif kind == EV_REACHED:
            run.reached.append(Mark(time, part))
        elif kind == EV_ESTIMATE and len(run.estimates) < MAX_ERRORS:
            pose, truth = _pose(event.get(EV_POSE)), _pose(event.get(EV_TRUTH))
            if pose is not None and truth is not None:
                run.estimates.append(Estimate(time, part, *errors(pose, truth)))


def cut_short_of(folder: Path, trace: Trace | None) -> str | None:
    """What a run folder without a report (its run was killed) says about where it ends,
    its events and its ``trace`` compared (:func:`~simmer.record.tracecheck.cut_short`); None
    if it has a report, or no events. PlotError if the events cannot be read."""
    from simmer.record.runfolder import REPORT_JSON
    from simmer.record.tracecheck import cut_short

    events = folder / EVENTS
    if (folder / REPORT_JSON).is_file() or not events.is_file():
        return None
    starts, times = [0.0], []  # when each part (reset) starts; each event's run time
    try:
        for _, event in event_objects(events):
            time = _float(event.get(EV_TIME))
            if math.isfinite(time):
                times.append(starts[-1] + time)
                if event.get(EV_TYPE) == EV_RESET:
                    starts.append(times[-1])
    except RunFolderError as exc:
        raise PlotError(str(exc)) from None
    if not times:
        return None
    if trace is None or not len(trace.time):
        return f"{cut_short(max(times), None, len(times))}; simmer replay --check replays them"
    part = int(trace.part[-1])
    end = (starts[part] if part < len(starts) else 0.0) + float(trace.time[-1])
    untraced = sum(time > end + 1e-9 for time in times)
    return f"{cut_short(max(times), end, untraced)}; the plots go to {end:.2f} s"


def _float(value: Any) -> float:
    """A JSON number, or "nan"/"inf"/"-inf", as a float; NaN for anything else."""
    if isinstance(value, bool):
        return math.nan
    if isinstance(value, int | float):
        return float(value)
    if isinstance(value, str) and value.strip().lower() in ("nan", "inf", "-inf", "+inf"):
        return float(value)
    return math.nan


def _pose(value: Any) -> Pose | None:
    """A finite ``[x, y, heading]`` pose, or None."""
    if isinstance(value, list) and len(value) == 3:
        pose = Pose(*(_float(v) for v in value))
        if all(map(math.isfinite, pose)):
            return pose
    return None


def _position(value: Any) -> tuple[float, float] | None:
    """(x, y) of a ``[x, y, heading]`` pose, or None."""
    if isinstance(value, list) and len(value) >= 2:
        x, y = _float(value[0]), _float(value[1])
        if math.isfinite(x) and math.isfinite(y):
            return x, y
    return None


# ----------------------------------------------------------------------------- plotting


def plot_run(
    folder: str | Path,
    say: Callable[[str], None] = log.warning,
    scan_time: float | None = None,
) -> list[Path]:
    """Write ``path.png`` and ``sensors.png`` (and ``scans.png``, every scan point, for a
    robot with a LiDAR; ``scan.png``, the scan that had ended by ``scan_time`` on the run's
    clock, if given) into a run folder and show them in its ``report.md``: written again
    from ``report.json`` for a recorded run, else linked from a ``report.md`` of some other
    origin if it does not show them yet; return the files written. A run cut short (killed:
    no report) is drawn as far as its trace goes, and ``say`` is told where its events and
    trace end (:func:`cut_short_of`)."""
    from simmer.record.runfolder import REPORT_JSON, write_report_md

    run = read_run(folder)
    scans = recorded_scans(run)
    one = None if scan_time is None else scan_at(scans, scan_time)
    if (said := cut_short_of(run.folder, run.trace)) is not None:
        say(said)
    path, sensors, report = (run.folder / name for name in (PATH_IMAGE, SENSORS_IMAGE, REPORT_FILE))
    images = [path, sensors, *([run.folder / LOCALIZATION_IMAGE] if run.estimates else [])]
    images += [run.folder / SCANS_IMAGE] if scans else []
    images += [run.folder / SCAN_IMAGE] if one is not None else []
    try:
        for image in (*images, report):  # none is drawn if one cannot be written
            check_target(image)
        write_path_plot(run, path)
        write_sensor_plot(run, sensors)
        if run.estimates:
            write_localization_plot(run, run.folder / LOCALIZATION_IMAGE)
        if scans:
            write_scans_plot(run, scans, run.folder / SCANS_IMAGE)
        if one is not None:
            write_scan_plot(run, one, run.folder / SCAN_IMAGE)
    except OSError as exc:  # UnsafeOutput names the file
        raise PlotError(str(exc) if isinstance(exc, UnsafeOutput) else _cannot(exc)) from None
    if (run.folder / REPORT_JSON).is_file():
        try:
            return [*images, write_report_md(run.folder)]
        except (OSError, ValueError) as exc:
            drawn = " and ".join(image.name for image in images)
            raise PlotError(f"drew {drawn}, but not report.md: {exc}") from None
    shown = [*IMAGES, *([LOCALIZATION_WORDS] if run.estimates else [])]
    shown += [SCANS_WORDS] if scans else []
    shown += [SCAN_WORDS] if one is not None else []
    try:
        return [*images, report] if link_from_report(report, shown) else images
    except (OSError, ValueError) as exc:
        drawn = " and ".join(image.name for image in images)
        raise PlotError(f"drew {drawn}, but not report.md: {exc}") from None


def _cannot(exc: OSError) -> str:
    """A file that could not be written, in one line."""
    return f"cannot write {exc.filename or 'the plots'}: {exc.strerror or exc}"


def link_from_report(report: Path, images: Sequence[tuple[str, str]]) -> bool:
    """Append a "## Plots" section showing the ``images`` (file name, words) that ``report``
    (if it exists) does not show yet; return whether it was changed."""
    if not report.is_file():
        return False
    check_target(report)  # a link is neither read nor written through
    data = read_at_most(
        report,
        MAX_REPORT_BYTES,
        "MAX_REPORT_BYTES",
        "more than a report; move it away to have a new one written",
    )
    text = data.decode("utf-8")
    missing = [(name, alt) for name, alt in images if f"]({name}" not in text]
    if not missing:
        return False
    section = "\n".join(f"![{alt}]({name})\n" for name, alt in missing)
    lead = "" if text.endswith("\n\n") else "\n" if text.endswith("\n") else "\n\n"
    write_text(report, f"{text}{lead}## Plots\n\n{section}")
    return True


def write_path_plot(run: RecordedRun, target: Path) -> PixelMap:
    """Draw the path over the maze into ``target``; return where world points land in it."""
    from matplotlib import style

    with style.context("default"):
        fig, ax = _path_figure(run)
        save_png(fig, target)
        origin, unit = ax.transData.transform([(0.0, 0.0), (1.0, 1.0)])
        height = fig.bbox.height
    return PixelMap(origin[0], unit[0] - origin[0], height - origin[1], origin[1] - unit[1])


def write_localization_plot(run: RecordedRun, target: Path) -> None:
    """Draw the program's estimate's error against time into ``target``: inches and degrees
    off the truth, the tolerances and when it localized (within both from then on)."""
    from matplotlib import style
    from matplotlib.figure import Figure

    offsets = run.trace.offsets()
    times = [e.time + offsets[min(e.part, len(offsets) - 1)] for e in run.estimates]
    since = localized_at(
        [(t, e.position, e.heading) for e, t in zip(run.estimates, times, strict=True)]
    )
    with style.context("default"):
        fig = Figure(figsize=(12.0, 5.5), dpi=DPI, layout="constrained")
        top, bottom = fig.subplots(2, 1, sharex=True)
        panels = (
            (top, [e.position for e in run.estimates], POSITION_TOLERANCE, "position error (in)"),
            (bottom, [e.heading for e in run.estimates], HEADING_TOLERANCE, "heading error (°)"),
        )
        for ax, values, tolerance, label in panels:
            unit = label[label.index("(") + 1 : -1]
            ax.plot(times, values, marker=".", lw=1.2, color=COMMAND_COLOR)
            ax.axhline(
                tolerance,
                color=START_COLOR,
                ls="--",
                lw=1.0,
                label=f"tolerance {tolerance:g} {unit}",
            )
            if since is not None:
                ax.axvline(since, color=PATH_COLOR, lw=1.5, label="localized")
            ax.set_ylabel(label)
            ax.set_ylim(bottom=0)
            ax.grid(alpha=0.3)
            ax.legend(loc="upper right", fontsize=9)
        bottom.set_xlabel("time (s)")
        when = f"localized at {since:.2f} s" if since is not None else "never localized"
        fig.suptitle(
            f"The program's estimate against the truth in {run.folder.resolve().name}: {when}\n"
            f"{len(run.estimates)} estimates; localized: within {POSITION_TOLERANCE:g} in and "
            f"{HEADING_TOLERANCE:g}° from then on",
            fontsize=12,
        )
        save_png(fig, target)


def write_sensor_plot(run: RecordedRun, target: Path) -> None:
    """Draw each sensor's readings against time into ``target``, commands marked."""
    from matplotlib import style

    with style.context("default"):
        save_png(_sensor_figure(run), target)


def recorded_scans(run: RecordedRun) -> list[tuple[float, RecordedScan]]:
    """The run's LiDAR scans (``scans.csv``), each with its time on the run's clock (the
    parts of a run with resets one after the other, as sensors.png plots them); [] if it
    recorded none. PlotError if the file cannot be read."""
    path = run.folder / SCANS
    if not path.is_file():
        return []
    try:
        scans = read_scans(path)
    except RunFolderError as exc:
        raise PlotError(str(exc)) from None
    offsets, parts = run.trace.offsets(), run.trace.parts
    part, timed, seen = 0, [], set[str]()
    for scan in scans:
        if scan.number == 1 and scan.device in seen:  # a reset: the scans count from 1 again
            part, seen = part + 1, set()
        seen.add(scan.device)
        timed.append((scan.time + float(offsets[min(part, parts - 1)]), scan))
    return timed


def scan_at(scans: Sequence[tuple[float, RecordedScan]], time: float) -> tuple[float, RecordedScan]:
    """The latest scan (of the first LiDAR) that ended by ``time`` on the run's clock, with
    its time on that clock; PlotError if none had."""
    if not scans:
        raise PlotError("the run recorded no LiDAR scans (its robot has no lidar device)")
    first = scans[0][1].device
    ended = [(at, scan) for at, scan in scans if scan.device == first and at <= time + 1e-9]
    if not ended:
        raise PlotError(
            f"no scan of {first} had ended by {time:g} s (the first ended at {scans[0][0]:g} s)"
        )
    return ended[-1]


def write_scan_plot(run: RecordedRun, timed: tuple[float, RecordedScan], target: Path) -> None:
    """Draw one scan (with its time on the run's clock) into ``target``: its points over the
    maze, the robot where it was when the scan ended, and beside it the distances as the
    program reads them (a polar plot, 0 degrees at the LiDAR's front, clockwise)."""
    from matplotlib import style
    from matplotlib.figure import Figure

    at, scan = timed
    trace = run.trace
    times = trace.run_time()
    pose = (
        float(np.interp(at, times, trace.x)),
        float(np.interp(at, times, trace.y)),
        float(np.interp(at, times, np.degrees(np.unwrap(np.radians(trace.heading))))),
    )
    with style.context("default"):
        maze = Maze.from_settings(run.settings)
        scale = max(maze.width, maze.height) / PAGE_INCHES
        width, height = maze.width / scale + 0.8, maze.height / scale + 2.2
        fig = Figure(figsize=(width + height * 0.6, height), dpi=DPI, layout="constrained")
        ax = fig.add_subplot(1, 2, 1)
        handles = _draw_path(ax, run, scale, commands=False)
        _draw_robot(ax, run.settings, pose, SCAN_RGB)
        handles.append(_line(SCAN_COLOR, "-", "the robot when the scan ended"))
        hit = ~np.isnan(scan.x)
        ax.plot(scan.x[hit], scan.y[hit], "o", ms=3, color=SCAN_COLOR, zorder=9)
        handles.append(_line(SCAN_COLOR, "o", f"scan {scan.number} of {_shown(scan.device)}"))
        ax.set_title(
            f"{_shown(scan.device)}'s scan {scan.number}, ended at {scan.time:.2f} s\n"
            f"{_title(run)}",
            fontsize=12,
        )
        fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=9)
        polar = cast("PolarAxes", fig.add_subplot(1, 2, 2, projection="polar"))
        polar.set_theta_zero_location("N")
        polar.set_theta_direction(-1)  # clockwise, as the LiDAR's angles go
        read = scan.distances > 0
        radians = np.radians(scan.angles)
        polar.plot(radians[read], scan.distances[read], "o", ms=3, color=SCAN_COLOR)
        missing = int((~read).sum())
        polar.set_title(
            f"As read: distance (in) by angle from the LiDAR's front\n"
            f"{len(scan.distances)} beams, {missing} with no return (read as 0)",
            fontsize=11,
        )
        save_png(fig, target)


def write_scans_plot(
    run: RecordedRun, scans: Sequence[tuple[float, RecordedScan]], target: Path
) -> None:
    """Draw every scan point of the run over the maze into ``target``, coloured by time, under
    the path driven."""
    from matplotlib import style
    from matplotlib.figure import Figure

    with style.context("default"):
        maze = Maze.from_settings(run.settings)
        scale = max(maze.width, maze.height) / PAGE_INCHES
        width, height = maze.width / scale + 1.6, maze.height / scale + 2.2
        fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
        ax = fig.add_subplot()
        handles = _draw_path(ax, run, scale, commands=False)
        times = np.concatenate([np.full(len(scan.x), at) for at, scan in scans])
        xs = np.concatenate([scan.x for _, scan in scans])
        ys = np.concatenate([scan.y for _, scan in scans])
        hit = ~np.isnan(xs)
        shown = ax.scatter(
            xs[hit], ys[hit], s=1.5, c=times[hit], cmap="plasma", zorder=3, rasterized=True
        )
        fig.colorbar(shown, ax=ax, label="time of the scan (s)", shrink=0.8)
        devices = sorted({_shown(scan.device) for _, scan in scans})
        handles.append(_line("#cc4778", "o", f"scan points ({int(hit.sum()):,})"))
        ax.set_title(
            f"Every scan point of {', '.join(devices)}: {len(scans):,} scans\n{_title(run)}",
            fontsize=12,
        )
        fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=9)
        save_png(fig, target)


def save_png(
    fig: Figure, target: Path, *, run_folder: bool = True, dpi: float | None = None
) -> None:
    """Write a figure as PNG with the Agg canvas (no pyplot, no window), safely
    (:func:`~simmer.record.safefile.replacing`: never through a link at its name; into a run
    folder unless ``run_folder`` is False), at ``dpi`` (None: the figure's)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    drawable_texts(fig)
    FigureCanvasAgg(fig)
    with replacing(target, run_folder=run_folder) as temp:
        fig.savefig(temp, dpi=fig.dpi if dpi is None else dpi, format="png")


def drawable_texts(fig: Figure) -> None:
    """Pass every text of ``fig`` through :func:`~simmer.untrusted.drawable` and take it
    literally: titles, labels and legends hold a run folder's names and a program's text, and
    a lone surrogate stopped matplotlib drawing, as did a ``$`` pair read as mathematics. A
    line break stays one (matplotlib draws it; every plot's title has two lines), and each
    line is cleaned and bounded on its own."""
    from matplotlib.text import Text

    for text in fig.findobj(Text):
        lines = text.get_text().split("\n")
        text.set_text("\n".join(drawable(line, _has_glyph) for line in lines))
        text.set_parse_math(False)


@cache
def _glyphs() -> frozenset[int]:
    """The characters matplotlib's default font has glyphs for (as code points)."""
    from matplotlib.font_manager import FontProperties, findfont, get_font

    return frozenset(get_font(findfont(FontProperties())).get_charmap())


def _has_glyph(char: str) -> bool:
    """Whether matplotlib's default font draws ``char`` (else it warns and draws a box)."""
    return ord(char) in _glyphs()


def _title(run: RecordedRun) -> str:
    """The second title line: time, distance, commands, collisions, block, resets, seed,
    configuration."""
    trace = run.trace
    duration = float(trace.run_time()[-1])
    parts = [f"{duration:.1f} s", f"{trace.length():.0f} in driven"]
    nans = sum(c.nan for c in run.commands)
    parts.append(f"{len(run.commands)} commands" + (f" ({nans} answered NaN)" if nans else ""))
    parts.append(f"{len(run.collisions)} collision{'s' if len(run.collisions) != 1 else ''}")
    if run.reached:
        parts.append(f"block reached at {run.reached[0].time:.2f} s")
    if trace.parts > 1:
        parts.append(f"{trace.parts - 1} reset{'s' if trace.parts > 2 else ''}")
    if run.seed is not None:
        parts.append(f"seed {run.seed}")
    if run.source:
        parts.append(f"config {_shown(Path(run.source).name)}")
    return " · ".join(parts)


def _shown(name: str) -> str:
    """A name read from a run folder as a title shows it: at most :data:`MAX_SHOWN_CHARS`
    characters, its ``$`` kept as text (matplotlib would read math between two)."""
    if len(name) > MAX_SHOWN_CHARS:
        name = name[:MAX_SHOWN_CHARS] + "..."
    return name.replace("$", r"\$")


def _path_figure(run: RecordedRun) -> tuple[Figure, Axes]:
    """The path figure: floor, solid cells, walls, block, start, path, commands, collisions."""
    from matplotlib.figure import Figure

    maze = Maze.from_settings(run.settings)
    scale = max(maze.width, maze.height) / PAGE_INCHES
    width = maze.width / scale + 0.8
    height = maze.height / scale + 2.2
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    ax = fig.add_subplot()
    handles = _draw_path(ax, run, scale)
    ax.set_title(f"Path of the run in {run.folder.resolve().name}\n{_title(run)}", fontsize=12)
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 5), fontsize=9)
    return fig, ax


def _draw_path(ax: Axes, run: RecordedRun, scale: float, commands: bool = True) -> list[Any]:
    """Draw the maze, block, start, path, end pose, collisions and (with ``commands``) the
    numbered commands on ``ax``, page-sized by ``scale`` (inches of maze per inch of page);
    return the legend's entries."""
    settings, trace = run.settings, run.trace
    maze = Maze.from_settings(settings)
    margin = maze.cell * 0.15
    ax.set_facecolor(rgb(settings.background_color))
    zones = Zones.from_settings(settings) if "gripper" in run.kinds.values() else None
    target = run.scenario.target if run.scenario else None
    maze_scene = maze_items(maze, settings, Look.PAGE, zones, target)
    draw_items(ax, maze_scene)
    walls = next(item for item in maze_scene if isinstance(item, Walls))
    wall = _line(rgb(walls.color), "-", "wall")
    handles: list[Any] = []
    start, block = _draw_block_and_start(ax, settings, run.scenario, run.handled is None)
    if run.handled is not None:
        handles += _draw_handled(ax, run, run.handled)
        put_down = run.handled.put_down is not None
        block = _line(rgb(settings.block_color), "s", "block where it was put down", mec="black")
    for p in range(trace.parts):
        rows = trace.part == p
        ax.plot(trace.x[rows], trace.y[rows], color=PATH_COLOR, lw=2.4, zorder=4)
    end = (float(trace.x[-1]), float(trace.y[-1]), float(trace.heading[-1]))
    _draw_robot(ax, settings, end, TRAIL_COLOR, dashed=True)
    ax.plot(end[0], end[1], "s", ms=7, mfc=PATH_COLOR, mec="black", zorder=6)
    handles += [_line(PATH_COLOR, "-", "path driven"), start]
    handles.append(_line(PATH_COLOR, "s", "end (outline, heading)", mec="black"))
    if commands:
        handles += _draw_commands(ax, run, scale)
    if run.collisions:
        points = trace.positions(run.collisions)
        for i, mark in enumerate(run.collisions):
            points[i] = mark.pose or points[i]  # where the event says, if it says
        xs, ys = points.T
        ax.plot(xs, ys, "X", ms=12, mfc=COLLISION_COLOR, mec="white", mew=1.2, ls="", zorder=8)
        handles.append(_line(COLLISION_COLOR, "X", f"collision ({len(points)})", mec="white"))
    if run.reached:
        (x, y), mark = trace.positions(run.reached[:1])[0], run.reached[0]
        ax.plot(x, y, "*", ms=18, mfc="gold", mec="black", zorder=7)
        handles.append(_line("gold", "*", f"block reached ({mark.time:.2f} s)", mec="black"))
    handles += [block, wall] if run.handled is None or put_down else [wall]
    ax.set_xlim(-margin, maze.width + margin)
    ax.set_ylim(maze.height + margin, -margin)  # +y down the page, as in the window
    ax.set_aspect("equal")
    ax.set_xticks(np.arange(maze.cols + 1) * maze.cell)
    ax.set_yticks(np.arange(maze.rows + 1) * maze.cell)
    ax.tick_params(top=True, labeltop=True, labelsize=9)
    ax.set_xlabel("x (inches)")
    ax.set_ylabel("y (inches, down)")
    return handles


def _draw_block_and_start(
    ax: Axes, settings: Settings, scenario: RecordedScenario | None = None, block: bool = True
) -> tuple[Any, Any]:
    """The block (unless ``block`` is False: a project run's block is drawn where it was put
    down) and the robot's outline and heading at the start (a project run's drawn ones if
    known); legend entries for the start and the block."""
    polygon = placed_block(settings, scenario.block if scenario is not None else None)
    start = scenario.start if scenario is not None else (
        *settings.robot_start_position, settings.robot_start_rotation
    )  # fmt: skip
    if block:
        draw_items(ax, block_items(polygon, settings, Look.PAGE))
    _draw_robot(ax, settings, start, START_RGB)
    ax.plot(start[0], start[1], "o", ms=8, mfc=START_COLOR, mec="white", zorder=6)
    return (
        _line(START_COLOR, "o", "start (outline, heading)", mec="white"),
        _line(rgb(settings.block_color), "s", "block", mec="black"),
    )


PICKUP_COLOR = "#1a9850"
DELIVERY_COLOR = "#6a3d9a"


def _pose_at(trace: Trace, time: float) -> tuple[float, float, float]:
    """The robot's pose at the first trace sample at or after ``time`` of the run's first
    part (the milestones' clock), or its last sample; the gripper acts between steps, so a
    sample has the pose it acted at."""
    rows = np.flatnonzero(trace.part == 0)
    at = rows[min(int(np.searchsorted(trace.time[rows], time - 1e-9)), len(rows) - 1)]
    return float(trace.x[at]), float(trace.y[at]), float(trace.heading[at])


def _draw_handled(ax: Axes, run: RecordedRun, handled: Handled) -> list[Any]:
    """A project run's block: faint where it lay, solid where it was put down (moved with the
    robot from the pickup on, as the gripper holds it), a mark at the robot's place at the
    pickup and at the delivery; their legend entries."""
    from matplotlib.patches import Polygon

    settings, scenario = run.settings, run.scenario
    at = scenario.block if scenario is not None else None
    lying = placed_block(settings, at)
    colour = rgb(settings.block_color)
    ax.add_patch(Polygon(lying, closed=True, fc=colour, ec="black", ls="--", alpha=0.35, zorder=3))
    handles = [_line(colour, "s", "block where it lay (faint)", mec="black")]
    px, py, ph = _pose_at(run.trace, handled.picked_up)
    ax.plot(px, py, "^", ms=13, mfc=PICKUP_COLOR, mec="white", mew=1.2, zorder=9)
    handles.append(_line(PICKUP_COLOR, "^", f"picked up ({handled.picked_up:.1f} s)", mec="white"))
    if handled.put_down is not None:
        put = _pose_at(run.trace, handled.put_down)
        polygon = put_down_block(settings, at, (px, py, ph), put)
        draw_items(ax, block_items(polygon, settings, Look.PAGE))
        x, y, _ = put
        ax.plot(x, y, "v", ms=13, mfc=DELIVERY_COLOR, mec="white", mew=1.2, zorder=9)
        where = "delivered to" if handled.delivered else "put down in"
        said = f"{where} {handled.zone or 'a zone'} ({handled.put_down:.1f} s)"
        handles.append(_line(DELIVERY_COLOR, "v", said, mec="white"))
    return handles


def _draw_robot(
    ax: Axes,
    settings: Settings,
    pose: tuple[float, float, float],
    color: Color,
    dashed: bool = False,
) -> None:
    """The robot's outline at ``pose`` and an arrow along its heading, under the path."""
    draw_items(ax, robot_items(placed_robot(settings, pose), settings, Look.PAGE, color, dashed))


def _draw_commands(ax: Axes, run: RecordedRun, scale: float) -> list[Any]:
    """Command numbers along the path, at the pose where each was sent: commands sent close
    together share one label ("4–9"), so labels neither overlap nor number more than about
    :data:`MAX_PATH_LABELS`; a dot where each label points, a red one at each NaN reply.
    ``scale``: world inches per inch of the page."""
    if not run.commands:
        return []
    points = run.trace.positions(run.commands)
    widest = 2 * len(str(len(run.commands))) + 1
    width = (widest * 0.6 * LABEL_POINTS / 72 + 0.1) * scale
    labels = _labels(points, max(LABEL_SPACING, width, run.trace.length() / MAX_PATH_LABELS))
    anchors = [anchor for anchor, _ in labels]
    nan = [i for i, c in enumerate(run.commands) if c.nan]
    for chosen, color, size in ((anchors, COMMAND_COLOR, 16), (nan, NAN_COLOR, 24)):
        xs, ys = points[chosen].T
        ax.scatter(xs, ys, s=size, c=color, edgecolors="white", lw=0.6, zorder=6)
    for anchor, text in labels:
        ax.annotate(
            text,
            points[anchor],
            xytext=(5, 5),
            textcoords="offset points",
            fontsize=LABEL_POINTS,
            color=COMMAND_COLOR,
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85},
            zorder=8,
        )
    handles = [_line(COMMAND_COLOR, "o", "commands n–m sent from here", mec="white")]
    if nan:
        handles.append(_line(NAN_COLOR, "o", "command answered NaN", mec="white"))
    return handles


def _labels(points: FloatArray, spacing: float) -> list[tuple[int, str]]:
    """Labels of command numbers, (index of the point labelled, text), at least ``spacing``
    apart: a run of consecutive commands within ``spacing`` of its first one is one range
    ("4–9"); ranges at a place labelled before (after a reset, or driving back) join its label,
    one a line."""
    groups: list[tuple[int, int]] = []
    for i, (x, y) in enumerate(points.tolist()):
        if groups and math.dist((x, y), points[groups[-1][0]]) < spacing:
            groups[-1] = (groups[-1][0], i)
        else:
            groups.append((i, i))
    labels: dict[int, list[str]] = {}
    for first, last in groups:
        text = str(first + 1) if first == last else f"{first + 1}–{last + 1}"
        near = (a for a in labels if math.dist(points[a], points[first]) < spacing)
        labels.setdefault(next(near, first), []).append(text)
    return [
        (anchor, "\n".join(texts if len(texts) <= 3 else [texts[0], "…", texts[-1]]))
        for anchor, texts in labels.items()
    ]


def _line(color: Any, marker: str, label: str, mec: str | None = None) -> Any:
    """A legend entry."""
    from matplotlib.lines import Line2D

    if marker == "-":
        return Line2D([], [], color=color, lw=2.5, label=label)
    return Line2D([], [], color=color, marker=marker, ls="", ms=9, mec=mec or color, label=label)


def sensor_panels(run: RecordedRun) -> list[tuple[str, list[str]]]:
    """The sensor plot's panels, (y-axis label, sensor ids), in trace order: one per sensor
    kind the manifest names, else one per id prefix (the letters before the digits)."""
    panels: dict[str, list[str]] = {}
    for name in run.trace.sensors:
        device, dash, suffix = name.partition("-")  # an IMU's axis: i0-1
        kind = run.kinds.get(name) or run.kinds.get(device)
        if kind is not None:
            unit = SENSOR_UNITS.get(kind + dash + suffix) or SENSOR_UNITS.get(kind, "reading")
            label = f"{kind}: {unit}"
        else:
            prefix = re.match(r"\D*", name)
            label = f"{prefix.group() if prefix else name}…: reading"
        panels.setdefault(label, []).append(name)
    return list(panels.items())


def _sensor_figure(run: RecordedRun) -> Figure:
    """Readings against time: a lane of numbered commands, then a panel per kind of sensor
    (:func:`sensor_panels`) with a line per sensor."""
    from matplotlib.figure import Figure

    trace = run.trace
    offsets, time = trace.offsets(), trace.run_time()
    groups = sensor_panels(run) or [("", [])]
    fig = Figure(figsize=(12.0, 2.0 + 2.6 * len(groups)), dpi=DPI, layout="constrained")
    lane, *axes = fig.subplots(
        len(groups) + 1, 1, sharex=True, height_ratios=[0.45] + [3.0] * len(groups)
    )
    _command_lane(lane, run, trace.run_times(run.commands), float(time[-1] - time[0]))
    for ax, (unit, names) in zip(axes, groups, strict=True):
        read = False
        for name in names:
            values = trace.sensors[name].copy()
            values[~np.isfinite(values)] = np.nan  # no reading yet, or a failed one: a gap
            seen = bool(np.isfinite(values).any())
            label = name if seen else f"{name} (never read)"
            ax.plot(time, values, lw=1.6, label=label, drawstyle="steps-post")
            read = read or seen
        if names:
            ax.legend(loc="upper right", fontsize=9, ncols=min(len(names), 6))
        if not read:
            ax.set_yticks([])
            say = "no command read these sensors" if names else "no sensors in the trace"
            ax.text(0.5, 0.5, say, ha="center", va="center", transform=ax.transAxes)
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
    for ax in (lane, *axes):
        for p in range(1, trace.parts):
            ax.axvline(offsets[p], color="grey", ls="--", lw=1.0)
    after_reset = " (parts after a reset follow on)" if trace.parts > 1 else ""
    axes[-1].set_xlabel(f"time (s){after_reset}")
    pad = max(float(time[-1] - time[0]), 1.0) * 0.01  # a command at 0 s clear of the frame
    axes[-1].set_xlim(time[0] - pad, time[-1] + pad)
    fig.suptitle(f"Sensor readings in {run.folder.resolve().name}\n{_title(run)}", fontsize=12)
    return fig


def _command_lane(ax: Axes, run: RecordedRun, times: FloatArray, span: float) -> None:
    """A tick at every command's time (red: answered NaN), numbered as on the path, at most
    :data:`MAX_TIME_LABELS` numbers across the ``span`` seconds shown."""
    ax.set_yticks([])
    ax.set_ylim(0.0, 1.0)
    ax.set_ylabel("commands", rotation=0, ha="right", va="center", fontsize=9)
    if not run.commands:
        ax.text(0.5, 0.5, "no commands", ha="center", va="center", transform=ax.transAxes)
        return
    nan = np.array([c.nan for c in run.commands], dtype=bool)
    ax.vlines(times[~nan], 0.08, 0.5, color=COMMAND_COLOR, lw=1.0)
    ax.vlines(times[nan], 0.08, 0.5, color=NAN_COLOR, lw=1.6)
    last = -math.inf
    for command, t in zip(run.commands, times.tolist(), strict=True):
        if t - last >= (span or 1.0) / MAX_TIME_LABELS:
            color = NAN_COLOR if command.nan else COMMAND_COLOR
            ax.text(t, 0.55, str(command.number), fontsize=7, color=color, ha="center")
            last = t
