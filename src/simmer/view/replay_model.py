"""What a replay shows, without a display: a recorded run re-simulated into frames, its
commands, whether it matches its recording, and the playhead moving through it.

:meth:`Recording.load` re-simulates a run folder once, up front, in the calling thread: the
configuration and seed from ``manifest.json``, the inputs from ``events.jsonl``
(:func:`simmer.world.replay.feed`). On the way it keeps a :class:`Frame` at every frame time
(:data:`FPS` a simulated second, the trace's rate, counted on across resets like a video), and
writes the re-simulated trace to compare with the recorded ``trace.csv``
(:mod:`simmer.record.tracecheck`). Seeking then only picks a frame: nothing is simulated again.
A frame is kept small (the sensors' shapes packed into one array, the robot placed again when
drawn): about 2 KB, 4 MB a simulated minute.

Times on the timeline are seconds from the start of the recording, going on across resets
(where the simulation's own clock starts again at 0). :class:`Playhead` is the state a window
changes with its keys (play, pause, speed, seek, next and previous command); it knows only a
:class:`Timeline`, so it can be tested with made-up numbers.
"""

from __future__ import annotations

import logging
import math
import platform
import tempfile
from bisect import bisect_right
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import simmer
from simmer.colors import Color
from simmer.devices.base import Circle, Segment, Shape
from simmer.errors import ConfigError, ReplayError, RunFolderError
from simmer.geometry import FloatArray, Pose, Vec2
from simmer.localize.belief import Belief
from simmer.record.reader import EVENTS, TRACE, read_trace_rows
from simmer.record.runfolder import (
    MANIFEST,
    MAX_RUN_SECONDS,
    REPORT_JSON,
    library_versions,
    load_run,
    read_json,
    read_manifest,
    sensor_ids,
)
from simmer.record.trace import TraceWriter
from simmer.record.tracecheck import TraceDifference, TraceRows, cut_short, first_difference
from simmer.view.frames import FPS, FrameClock
from simmer.view.maker import LocalControls, SnapshotMaker
from simmer.view.snapshot import RobotLayout, Snapshot, StaticScene
from simmer.view.trail import TrailView
from simmer.world import Simulation
from simmer.world.events import CommandEvent, Event, ResetEvent
from simmer.world.outcome import OutcomeReport
from simmer.world.replay import feed, same_replies

log = logging.getLogger("simmer.replay")

__all__ = [
    "FPS",
    "SPEEDS",
    "Check",
    "Frame",
    "PackedShapes",
    "Playhead",
    "Recording",
    "ReplayCommand",
    "Timeline",
]

SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
"""Playback speeds, multiples of real time, that ``+`` and ``-`` step through."""


# ----------------------------------------------------------------------------- frames


@dataclass(frozen=True, slots=True)
class PackedShapes:
    """A frame's measurement shapes in one array: a row per shape, ``x1 y1 x2 y2`` for a
    segment and ``x y radius NaN`` for a circle; ``kinds`` (circle?, colour) is shared by the
    frames whose shapes are of the same kinds."""

    kinds: tuple[tuple[bool, Color], ...]
    values: FloatArray

    @classmethod
    def pack(cls, shapes: tuple[Shape, ...], like: PackedShapes | None = None) -> PackedShapes:
        """Pack ``shapes``, sharing ``like``'s kinds if they are the same."""
        kinds = tuple((isinstance(shape, Circle), shape.color) for shape in shapes)
        if like is not None and like.kinds == kinds:
            kinds = like.kinds
        values = np.array(
            [
                (*s.center, s.radius, math.nan) if isinstance(s, Circle) else (*s.start, *s.end)
                for s in shapes
            ],
            dtype=np.float64,
        ).reshape(len(shapes), 4)
        return cls(kinds, values)

    def unpack(self) -> tuple[Shape, ...]:
        """The shapes again."""
        return tuple(
            Circle(Vec2(a, b), c, color) if circle else Segment(Vec2(a, b), Vec2(c, d), color)
            for (circle, color), (a, b, c, d) in zip(self.kinds, self.values.tolist(), strict=True)
        )


@dataclass(frozen=True, slots=True)
class Frame:
    """What one frame of a replay draws, kept small (see the module doc); values that did not
    change since the frame before are shared with it."""

    time: float
    """Simulated seconds, as the HUD shows them (0 again after a reset)."""
    pose: Pose
    block: FloatArray
    layout: RobotLayout
    shapes: PackedShapes
    held: frozenset[str]
    outcome: OutcomeReport | None
    commands: tuple[CommandEvent, ...]
    switched_off: tuple[tuple[str, str], ...]
    trail: TrailView | None
    belief: Belief | None

    @classmethod
    def of(cls, snap: Snapshot, previous: Frame | None = None) -> Frame:
        """Keep what ``snap`` draws, sharing what is unchanged with ``previous``."""
        block, commands = snap.block, snap.commands
        if previous is not None:
            if np.array_equal(previous.block, block):
                block = previous.block
            if previous.commands == commands:
                commands = previous.commands
        return cls(
            time=snap.time,
            pose=snap.pose,
            block=block,
            layout=snap.layout,
            shapes=PackedShapes.pack(snap.shapes, previous.shapes if previous else None),
            held=snap.held,
            outcome=snap.outcome,
            commands=commands,
            switched_off=snap.switched_off,
            trail=snap.trail,
            belief=snap.belief,
        )

    def snapshot(self, *, paused: bool = False, speed: float = 1.0) -> Snapshot:
        """The snapshot to draw, with the replay's pause and speed for the HUD."""
        return Snapshot(
            time=self.time,
            pose=self.pose,
            block=self.block,
            layout=self.layout,
            robot=self.layout.place(self.pose),
            shapes=self.shapes.unpack(),
            paused=paused,
            speed=speed,
            held=self.held,
            outcome=self.outcome,
            commands=self.commands,
            switched_off=self.switched_off,
            trail=self.trail,
            belief=self.belief,
            target=self.outcome.project.target if self.outcome and self.outcome.project else None,
        )


@dataclass(frozen=True)
class ReplayCommand:
    """A command of the run: when, as re-simulated, and the replies the recording has."""

    time: float
    """Seconds from the start of the recording."""
    frame: int
    """The first frame that shows it done."""
    event: CommandEvent
    """As re-simulated (its ``time`` is the simulation's clock, 0 again after a reset)."""
    recorded: tuple[float, ...]

    @property
    def differs(self) -> bool:
        """Whether the re-simulation answered otherwise than the recording says."""
        return not same_replies(self.event.replies, self.recorded)


class _Collector:
    """An observer of the re-simulation: a frame at each frame time, and each command with
    the frame that first shows it."""

    def __init__(self, sim: Simulation, fps: int) -> None:
        self.maker = SnapshotMaker(sim)  # outcome, last commands and trail, as the window has
        self.controls = LocalControls(sim)
        self.clock = FrameClock(fps, sim.time)
        self.clock.frames = 1
        self.frames = [Frame.of(self.maker.snapshot(self.controls))]
        self.commands: list[tuple[float, int, CommandEvent]] = []
        self.offset = 0.0
        """Seconds of the recording before the last reset."""
        self.part_starts = [0.0]
        """Seconds from the start of the recording at which each part (reset) begins."""
        sim.add_observer(self)

    def __call__(self, event: Event) -> None:
        if isinstance(event, ResetEvent):
            self.offset += event.time
            self.part_starts.append(self.offset)
        elif isinstance(event, CommandEvent):
            self.commands.append((self.offset + event.time, len(self.frames), event))
        count = self.clock.due(event)
        if count:
            frame = Frame.of(self.maker.snapshot(self.controls), self.frames[-1])
            self.frames += [frame] * count

    def finish(self) -> None:
        """At the end: one more frame if the program showed a belief after the last frame
        (the estimate after its last move), as the run's video has it."""
        snap = self.maker.snapshot(self.controls)
        if snap.belief is not self.frames[-1].belief:
            self.frames.append(Frame.of(snap, self.frames[-1]))


# ----------------------------------------------------------------------------- the check


def _versions(simmer_version: str, libraries: dict[str, str]) -> str:
    """``SimMeR 2.0.0 (Python 3.11.7, numpy 1.26.4, numba 0.60.0)``."""
    others = ", ".join(f"{name} {libraries[name]}" for name in sorted(libraries))
    return f"SimMeR {simmer_version} ({others})"


@dataclass(frozen=True)
class Check:
    """Whether the re-simulation is the recorded run, and what differs first if not."""

    rows: int
    """Trace rows compared."""
    difference: TraceDifference | None
    difference_time: float | None
    """Seconds from the start of the recording of :attr:`difference`."""
    reply_differences: tuple[str, ...]
    """Each reply that came out otherwise (:func:`simmer.world.replay.replay`'s words)."""
    recorded_with: str
    replayed_with: str
    incomplete: str | None = None
    """Why the recording is incomplete, if it is."""
    no_trace: bool = False
    """The folder has no trace.csv to compare with."""

    @property
    def matches(self) -> bool:
        """The re-simulated trace and replies are the recorded ones."""
        return self.difference is None and not self.reply_differences and not self.no_trace

    def headline(self) -> str:
        """One line: matches, or where it first differs."""
        if self.difference is not None:
            return f"DIFFERS from the recording {self.difference.describe()}"
        if self.reply_differences:
            return f"DIFFERS from the recording: {self.reply_differences[0]}"
        if self.no_trace:
            return f"cannot be compared: the folder has no {TRACE}"
        if self.incomplete is not None:
            return f"matches the recording as far as it goes ({self.rows} trace rows, every reply)"
        return f"matches the recording ({self.rows} trace rows, every reply)"

    def lines(self) -> list[str]:
        """What the terminal and the window say about the re-simulation."""
        lines = [f"the re-simulation {self.headline()}"]
        if not self.matches:
            lines.append(f"recorded with {self.recorded_with}")
            lines.append(f"replayed with {self.replayed_with}")
        count = len(self.reply_differences)
        if count and self.difference is not None:
            lines.append(f"{count} {'reply differs' if count == 1 else 'replies differ'}")
        if self.incomplete is not None:
            lines.append(self.incomplete)
        return lines


# ----------------------------------------------------------------------------- the recording


@dataclass(frozen=True)
class Timeline:
    """Where the frames and commands of a replay are in time (no pictures)."""

    fps: int
    frames: int
    """Frames, the first at 0 s."""
    command_frames: tuple[int, ...]
    """The first frame that shows each command done, in order."""

    @property
    def duration(self) -> float:
        """Seconds from the first frame to the last."""
        return (self.frames - 1) / self.fps

    def frame_at(self, time: float) -> int:
        """The frame shown at ``time`` (the last one not after it)."""
        return min(self.frames - 1, max(0, math.floor(time * self.fps + 1e-6)))

    def frame_time(self, frame: int) -> float:
        """When frame ``frame`` is shown."""
        return min(max(frame, 0), self.frames - 1) / self.fps

    def command_at(self, frame: int) -> int:
        """The index of the last command done by ``frame`` (-1: none yet)."""
        return bisect_right(self.command_frames, frame) - 1


class Recording:
    """A run folder re-simulated for a replay (see the module doc); :meth:`load` makes one."""

    def __init__(
        self,
        folder: Path,
        scene: StaticScene,
        frames: list[Frame],
        commands: list[ReplayCommand],
        check: Check,
        seed: int,
        fps: int = FPS,
    ) -> None:
        self.folder = folder
        self.scene = scene
        self.frames = frames
        self.commands = commands
        self.check = check
        self.seed = seed
        self.timeline = Timeline(fps, len(frames), tuple(c.frame for c in commands))

    @property
    def duration(self) -> float:
        """Seconds from the first frame to the last."""
        return self.timeline.duration

    def snapshot(self, frame: int, *, paused: bool = False, speed: float = 1.0) -> Snapshot:
        """Frame ``frame`` to draw."""
        return self.frames[frame].snapshot(paused=paused, speed=speed)

    @classmethod
    def load(
        cls,
        folder: str | Path,
        fps: int = FPS,
        *,
        trust: bool = False,
        plugins: Sequence[str | Path] | None = None,
        max_seconds: float = MAX_RUN_SECONDS,
    ) -> Recording:
        """Re-simulate the run in ``folder``; :class:`ReplayError` (one line) if it cannot be
        (not a run folder, unreadable files, a configuration that no longer loads, plug-ins
        not trusted: :func:`simmer.record.load_run`, events beyond ``max_seconds``).

        A recording cut short (no ``report.json``: the run was killed or crashed) is replayed
        as far as its events and trace go, and :attr:`Check.incomplete` says so.
        """
        folder = Path(folder)
        manifest = _read_manifest(folder)
        try:
            config, seed, events = load_run(
                folder, trust=trust, plugins=plugins, max_seconds=max_seconds
            )
        except ReplayError:
            raise
        except ConfigError as exc:
            problem = exc.issues[0].render(exc.source) if exc.issues else str(exc)
            raise ReplayError(
                f"{folder / MANIFEST}: the recorded configuration no longer loads: {problem}"
            ) from None
        except KeyError as exc:
            raise ReplayError(f"{folder / MANIFEST} has no {exc}: not a run's manifest") from None
        except OSError as exc:
            raise ReplayError(f"cannot read the run in {folder}: {exc}") from None
        except ValueError as exc:  # each names its file
            raise ReplayError(str(exc)) from None
        recorded = _read_recorded_trace(folder)
        incomplete = _incomplete(folder, events, recorded)
        until = _replay_until(events, recorded) if incomplete else None
        max_steps = int(max_seconds * config.settings.frame_rate)
        if until is not None and until > max_steps:
            raise ReplayError(
                f"{folder / TRACE}: a row at step {until:,} is beyond the replay limit of "
                f"{max_steps:,} steps ({max_seconds:g} s; --max-seconds raises it)"
            )
        sim = Simulation(config, seed=seed)
        quiet = _errors_only(logging.getLogger("simmer"))  # its warnings were seen when it ran
        with quiet, tempfile.TemporaryDirectory(prefix="simmer-replay-") as tmp:
            replayed_path = Path(tmp) / TRACE
            writer = TraceWriter(replayed_path, sensor_ids(config), config.settings.frame_rate)
            writer.begin(sim.time, sim.steps, sim.robot.pose)
            sim.add_observer(writer)
            collector = _Collector(sim, fps)
            try:
                result = feed(sim, events, until)
            finally:
                writer.close()
            collector.finish()
            replayed = read_trace_rows(replayed_path)
        difference = (
            None
            if recorded is None
            else first_difference(recorded, replayed, complete=incomplete is None)
        )
        if incomplete is not None:
            incomplete += f"; replayed up to {collector.offset + sim.time:.2f} s"
        beliefs = collector.maker.beliefs
        if beliefs.bad:
            log.warning(
                "%d shown belief(s) in %s could not be read and are not drawn (the first %s)",
                beliefs.bad,
                folder / EVENTS,
                beliefs.first_problem,
            )
        commands = _commands(collector, events)
        check = Check(
            rows=_compared_rows(recorded, replayed),
            difference=difference,
            difference_time=None if difference is None else _run_time(difference, collector),
            reply_differences=tuple(result.differences),
            recorded_with=_versions(
                str(manifest.get("simmer_version", "unknown")), _recorded_libraries(manifest)
            ),
            replayed_with=_versions(
                simmer.__version__, {"Python": platform.python_version(), **library_versions()}
            ),
            incomplete=incomplete,
            no_trace=recorded is None,
        )
        return cls(folder, StaticScene.of(sim), collector.frames, commands, check, seed, fps)


@contextmanager
def _errors_only(logger: logging.Logger) -> Iterator[None]:
    """Within ``with``: only errors from ``logger`` (and the loggers under it)."""
    level = logger.level
    logger.setLevel(max(level, logging.ERROR))
    try:
        yield
    finally:
        logger.setLevel(level)


def _read_manifest(folder: Path) -> dict[str, object]:
    """The manifest, or a :class:`ReplayError` saying why this is not a run folder."""
    if not folder.is_dir():
        raise ReplayError(f"{folder} is not a folder; give a run folder (simmer run --record DIR)")
    missing = [name for name in (MANIFEST, EVENTS) if not (folder / name).is_file()]
    if missing:
        raise ReplayError(
            f"{folder} is not a run folder: no {' or '.join(missing)} "
            "(record one with simmer run --record DIR)"
        )
    try:
        return read_manifest(folder)
    except OSError as exc:
        raise ReplayError(f"cannot read {folder / MANIFEST}: {exc}") from None
    except ValueError as exc:
        raise ReplayError(str(exc)) from None


def _compared_rows(recorded: TraceRows | None, replayed: TraceRows) -> int:
    """Rows of the recorded trace that the re-simulation was compared with: never more than
    the file holds (after ``kill -9`` it lacks its last second)."""
    if recorded is None:
        return 0
    keys = {key for key, _ in replayed.rows}
    return sum(key in keys for key, _ in recorded.rows)


def _recorded_libraries(manifest: dict[str, object]) -> dict[str, str]:
    """The versions of Python, numpy and numba the manifest says the run used."""
    known = manifest.get("platform")
    if not isinstance(known, dict):
        return {}
    names = {"python": "Python", "numpy": "numpy", "numba": "numba"}
    return {shown: str(known[key]) for key, shown in names.items() if key in known}


def _read_recorded_trace(folder: Path) -> TraceRows | None:
    """The recorded trace's rows (None: there is no trace.csv)."""
    path = folder / TRACE
    if not path.is_file():
        return None
    try:
        return read_trace_rows(path)
    except RunFolderError as exc:  # "cannot read PATH: ..."
        raise ReplayError(str(exc)) from None


def _incomplete(folder: Path, events: list[Event], recorded: TraceRows | None) -> str | None:
    """Why the recording is incomplete (None: it is complete): the recorder writes
    report.json when the run ends, however it ends, unless it is killed; it says there
    whether the recording stopped before the run did (a full disk). A run killed is cut
    short where its events and trace end (:func:`~simmer.record.tracecheck.cut_short`)."""
    if (folder / REPORT_JSON).is_file():
        try:
            stopped = read_json(folder / REPORT_JSON).get("recording_stopped")
        except (OSError, ValueError) as exc:
            raise ReplayError(str(exc)) from None
        return None if stopped is None else f"incomplete recording: {stopped}"
    starts = [0.0]  # seconds from the run's start at which each part (reset) begins
    for event in events:
        if isinstance(event, ResetEvent):
            starts.append(starts[-1] + event.time)
    end = recorded.end if recorded is not None else None
    trace_end = None
    if recorded is not None and end is not None and end[0] < len(starts):
        time = recorded.end_time
        trace_end = starts[end[0]] + time if math.isfinite(time) else None
    part, untraced = 0, 0
    for event in events:
        untraced += end is None or (part, event.step) > end
        part += isinstance(event, ResetEvent)
    events_end = starts[part] + events[-1].time if events else None
    said = cut_short(events_end, trace_end, untraced)
    if trace_end is None:
        return f"{said}; no {REPORT_JSON}: every reply is compared, the trace is not"
    return f"{said}; no {REPORT_JSON}: the trace is compared up to {trace_end:.2f} s"


def _replay_until(events: list[Event], recorded: TraceRows | None) -> int | None:
    """The step to replay to for an incomplete recording: its last event's, or the trace's
    last row's if that is later in the same part of the run (the trace can outlive the
    events when no input came for a while)."""
    resets = sum(isinstance(event, ResetEvent) for event in events)
    last = 0
    for event in events:
        last = 0 if isinstance(event, ResetEvent) else max(last, event.step)
    end = recorded.end if recorded is not None else None
    if end is not None and end[0] == resets:
        return max(last, end[1])
    return None


def _commands(collector: _Collector, events: list[Event]) -> list[ReplayCommand]:
    """The re-simulated commands with the replies the recording has for each."""
    recorded = [event.replies for event in events if isinstance(event, CommandEvent)]
    return [
        ReplayCommand(time, frame, event, recorded[i] if i < len(recorded) else ())
        for i, (time, frame, event) in enumerate(collector.commands)
    ]


def _run_time(difference: TraceDifference, collector: _Collector) -> float:
    """Seconds from the start of the recording of a trace difference (its trace time counts
    from the last reset before it)."""
    starts = collector.part_starts
    time = difference.time if math.isfinite(difference.time) else 0.0
    return starts[min(difference.part, len(starts) - 1)] + time


# ----------------------------------------------------------------------------- the playhead


class Playhead:
    """Where a replay is and how it moves: play or pause, speed, seeking, the next or previous
    command. Times are seconds from the start of the recording; the window calls
    :meth:`advance` with the wall-clock seconds since its last frame."""

    def __init__(self, timeline: Timeline) -> None:
        self.timeline = timeline
        self.time = 0.0
        self.playing = False
        self.speed = 1.0
        self._chosen: int | None = None
        """The command stepped to with next or previous, while the time stays there (several
        can be done by the same frame)."""

    @property
    def frame(self) -> int:
        """The frame shown now."""
        return self.timeline.frame_at(self.time)

    @property
    def command(self) -> int:
        """The index of the command to highlight: the last one done by now (-1: none)."""
        if self._chosen is not None:
            return self._chosen
        return self.timeline.command_at(self.frame)

    @property
    def at_end(self) -> bool:
        """Whether the last frame is shown."""
        return self.frame == self.timeline.frames - 1

    def toggle(self) -> None:
        """Play, or pause; playing at the end starts again from the beginning."""
        if not self.playing and self.at_end:
            self.seek(0.0)
        self.playing = not self.playing

    def advance(self, seconds: float) -> None:
        """``seconds`` of wall-clock time went by: move on if playing, stopping at the end."""
        if not self.playing:
            return
        end = self.timeline.duration
        self.seek(self.time + seconds * self.speed)
        if self.time >= end:
            self.playing = False

    def seek(self, time: float) -> None:
        """Go to ``time`` (kept within the recording)."""
        self.time = min(max(time, 0.0), self.timeline.duration)
        self._chosen = None

    def step(self, frames: int) -> None:
        """Pause and move ``frames`` frames on (or back, if negative)."""
        self.playing = False
        self.seek(self.timeline.frame_time(self.frame + frames))

    def faster(self) -> None:
        """The next speed up (at most 16 times real time)."""
        self.speed = next((s for s in SPEEDS if s > self.speed), SPEEDS[-1])

    def slower(self) -> None:
        """The next speed down (at least a quarter of real time)."""
        self.speed = next((s for s in reversed(SPEEDS) if s < self.speed), SPEEDS[0])

    def next_command(self) -> None:
        """Go to the next command: the first frame that shows it done."""
        target = self.command + 1
        if target < len(self.timeline.command_frames):
            self._go_to_command(target)

    def previous_command(self) -> None:
        """Go to the start of the highlighted command if the playhead is past it, else to
        the command before it (before the first: the start)."""
        current = self.command
        frames = self.timeline.command_frames
        if current >= 0 and self.time > self.timeline.frame_time(frames[current]) + 1e-9:
            self._go_to_command(current)
        elif current >= 1:
            self._go_to_command(current - 1)
        else:
            self.seek(0.0)

    def _go_to_command(self, index: int) -> None:
        self.seek(self.timeline.frame_time(self.timeline.command_frames[index]))
        self._chosen = index
