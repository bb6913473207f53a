"""The simulation: a world of maze, block and robot, stepped at a fixed rate.

One thread owns a :class:`Simulation`; transports hand it commands through a queue (see
``simmer.transport``) and never touch it themselves. All randomness comes from the run's seed,
one stream per source (each device, each drive's drawn bias: :meth:`Simulation.stream`), so a
run is repeatable from its seed and one source's draws never shift another's.
"""

from __future__ import annotations

import hashlib
import logging
import math
import threading
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from simmer.config.loader import load_config
from simmer.config.maze import Block, Maze, robot_outline
from simmer.config.models import SimConfig
from simmer.config.scenario import Scenario, draw_scenario
from simmer.config.zones import Zones
from simmer.devices import Axes, Device, Drive, Shape
from simmer.errors import CommandError, DeviceKindError, WrongThread, describe_exception
from simmer.geometry import (
    FloatArray,
    Pose,
    Vec2,
    place_polygon,
    polygon_hits_grid,
    robot_blocked,
    wrap_degrees,
)
from simmer.protocol import LENIENT_RULES, STOP_ID, Command, parse_commands, printable
from simmer.world.events import (
    BlockedMoveEvent,
    CollisionEndEvent,
    CollisionEvent,
    CommandEvent,
    Event,
    KeysEvent,
    Observer,
    PlaceEvent,
    ResetEvent,
    StepEvent,
)
from simmer.world.robot import Robot

log = logging.getLogger("simmer")

DEVICE_FAULTS = (Exception, SystemExit)
"""What a device's own code may raise without stopping the run (a ``sys.exit`` in a student's
device included); it switches that device off. Ctrl-C still stops everything."""
MANUAL_SPEED = 6.0  # in/s, BEHAVIOUR §3
MANUAL_TURN = 120.0  # deg/s
MANUAL_KEYS = "wasdqe"
STILL = Vec2(0.0, 0.0)
"""The robot's motion in a step in which it did not move."""

MAX_BLOCKED_LOGGED = 20
"""Blocked moves a run's log names one by one (each in a line of its own); past them it says
once that the rest are counted only (the outcome and the HUD count every one): a wall follower
turning against a wall for minutes would otherwise fill the log."""

BLOCKED_SHOWN = 2.0
"""Simulated seconds the window keeps showing a blocked move after it ended."""


@dataclass
class _Move:
    """The drive command moving now: what it was, and how far it got (:class:`BlockedMoveEvent`)."""

    command: str
    started: float
    amount: float
    unit: str
    done: float = 0.0
    blocked: int = 0


FLOAT32_MAX = float(np.finfo(np.float32).max)
"""The largest reading a 4-byte reply can carry; a device reading beyond it answers NaN."""


def source_stream(seed: int, source: str) -> np.random.Generator:
    """The random stream of one source of noise of a run seeded ``seed`` (``device:u0``):
    ``SeedSequence`` with a stable key from the source's name (:meth:`Simulation.stream`; a
    batch's robot draws from the same streams)."""
    digest = hashlib.blake2b(source.encode("utf-8"), digest_size=8).digest()
    key = int.from_bytes(digest, "little")
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(key,)))


class Answer(NamedTuple):
    """One command's reply ``value`` and, for a NaN, ``why`` (logged at ``level`` by whoever
    reports it)."""

    value: float
    level: int = logging.DEBUG
    why: str | None = None

    @classmethod
    def nan(cls, level: int, why: str) -> Answer:
        """A NaN reply and why."""
        return cls(math.nan, level, why)


class Simulation:
    """A headless, deterministic simulation of one robot in one maze.

    Use :meth:`from_config` to build one, :meth:`command` to talk to the robot as a control
    program would, and :meth:`step` / :meth:`run_until_idle` to let simulated time pass.
    A device whose own code raises is switched off until :meth:`reset` (see
    :attr:`switched_off`) instead of stopping the simulation.
    """

    def __init__(self, config: SimConfig, seed: int | None = None) -> None:
        self.config = config
        settings = config.settings
        self.seed = settings.run_seed(seed)
        self.maze = Maze.from_settings(settings)
        self.zones = Zones.from_settings(settings)
        self._dt = 1.0 / settings.frame_rate
        self._owner: int | None = None
        self.observers: list[Observer] = []
        self._simulate_list = settings.simulate_list
        self._lenient = settings.lenient_commands
        self._widest = FLOAT32_MAX if settings.reply_bytes == 4 else math.inf
        self._build()

    @classmethod
    def from_config(cls, path: str | Path | None = None, seed: int | None = None) -> Simulation:
        """Load a configuration file (None: the built-in default) and build a simulation."""
        return cls(load_config(path), seed=seed)

    def stream(self, source: str) -> np.random.Generator:
        """A fresh random generator for one source of noise (``device:u0``, ``bias:w0``).

        Each source's stream comes from the run's seed and the source's name alone
        (``SeedSequence`` with a stable key), so adding a sensor, removing one or polling a
        drive never changes another source's noise.
        """
        return source_stream(self.seed, source)

    def _build(self) -> None:
        """Create robot, block and devices at their start, each device with a fresh stream."""
        settings = self.config.settings
        self.scenario: Scenario = draw_scenario(settings, self.maze, self.zones, self.stream)
        self._block = Block(*self.scenario.block, settings.block_rotation, settings.block_size)
        self._carried = np.empty((4, 2))
        devices: list[Device] = []
        for spec in self.config.devices:
            kind = self.config.kinds.get(spec.kind)
            if kind is None:
                raise DeviceKindError(f"device kind {spec.kind!r} is no longer registered")
            devices.append(kind(spec.id, spec.params, self.stream(f"device:{spec.id}")))
        start = self.scenario.start
        self._robot = Robot(robot_outline(settings), start, settings.robot_height, devices)
        self._switched_off: dict[str, str] = {}
        self._working = dict(self._robot.devices)
        """The devices not switched off, by id: what a command reaches."""
        self._updating = list(self._robot.updating)
        self._listed = [self._robot.sensors[i] for i in dict.fromkeys(self._simulate_list)]
        for drive in self._robot.drives.values():
            drive.bind_motors([self._robot.motors[m] for m in drive.settings.motors])
            if settings.rand_bias:
                drive.set_bias(self._draw_bias(drive))
        self._time = 0.0
        self.steps = 0
        self.collisions = 0
        self.blocked_steps = 0
        self.blocked_moves = 0
        """Drive commands some of whose steps a wall or the block stopped."""
        self.last_blocked: BlockedMoveEvent | None = None
        """The last of them, for the HUD."""
        self._moving: _Move | None = None
        self._was_blocked = False
        self.manual_keys: frozenset[str] = frozenset()
        self._lenient_warned: set[tuple[str, str]] = set()

    def _draw_bias(self, drive: Drive) -> Axes:
        """``rand_bias``: x, y ~ N(0, linear); rotation ~ N(0, rotational) for a translating
        drive (degrees per inch), N(0, linear) for a rotating one (a fraction, like x and y)."""
        linear, rotational = self.config.settings.bias_strength
        rng = self.stream(f"bias:{drive.id}")
        x, y = rng.normal(0.0, linear, 2) if linear else (0.0, 0.0)
        spread = linear if drive.rotational else rotational
        rotation = float(rng.normal(0.0, spread)) if spread else 0.0
        return Axes(x=float(x), y=float(y), rotation=rotation)

    # ----------------------------------------------------------------- the World protocol

    @property
    def time(self) -> float:
        """Simulated seconds since the start."""
        return self._time

    @property
    def dt(self) -> float:
        """Seconds per step (1 / frame_rate)."""
        return self._dt

    @property
    def block(self) -> Block:
        """The block."""
        return self._block

    @property
    def robot(self) -> Robot:
        """The robot."""
        return self._robot

    @property
    def switched_off(self) -> Mapping[str, str]:
        """Devices switched off because their code raised, by id, with the reason (e.g.
        ``{"t0": "ZeroDivisionError: division by zero (tof.py line 12)"}``); emptied by
        :meth:`reset`. A read-only live view."""
        return MappingProxyType(self._switched_off)

    # ----------------------------------------------------------------- commands

    def command(self, message: str, client: str = "") -> list[float]:
        """Execute a message such as ``"w0-6,u0"``; one reply value per command, in order.

        A drive answers +inf when accepted and NaN when a drive is busy; a malformed command or
        an unknown device answers NaN and logs why. ``client`` names the sender in the event
        stream. (A transport parses a message once, as it decodes it, and calls
        :meth:`replies`, which returns why with each NaN.)"""
        values, failed = self.replies(
            parse_commands(message, lenient=self._lenient), message, client
        )
        for answer in failed:
            if answer.why is not None:
                log.log(answer.level, "%s", answer.why)
        return values

    def parse(self, message: str) -> tuple[Command, ...]:
        """The commands of a message, read as this configuration says (strictly, or the
        original SimMeR's lenient way)."""
        return parse_commands(message, lenient=self._lenient)

    def replies(
        self, commands: Sequence[Command], message: str, client: str = ""
    ) -> tuple[list[float], list[Answer]]:
        """Execute the parsed ``commands`` of ``message``: one value per command, in order, and
        the NaN answers among them with why (the caller logs as much of that as it wants and
        tells the client). No object is built for a command that succeeds: a LiDAR's
        whole-scan read is 361 commands."""
        self._before(commands)
        values: list[float] = []
        failed: list[Answer] = []
        for command in commands:
            reply = self._reply(command)
            if type(reply) is float:
                values.append(reply)
            else:
                assert isinstance(reply, Answer)
                failed.append(reply)
                values.append(reply.value)
        if self.observers:
            self.emit(CommandEvent(self._time, message, tuple(values), self.steps, client))
        return values, failed

    def _before(self, commands: Sequence[Command]) -> None:
        """What comes before a message's commands run: the thread check, lenient warnings."""
        if self._owner is not None:
            self._check_thread("command")
        for command in commands:
            if command.lenient:
                self._warn_lenient(command)

    def _warn_lenient(self, command: Command) -> None:
        """Say once per device and rule that a command was read the originals' way."""
        for rule in command.lenient:
            if (command.device, rule) in self._lenient_warned:
                continue
            self._lenient_warned.add((command.device, rule))
            log.warning(
                "command '%s' read as %s-%g: %s, as in the original SimMeR (said once per device; "
                "lenient_commands = false makes such commands answer NaN)",
                printable(command.text.strip()),
                printable(command.device),
                command.value,
                LENIENT_RULES[rule],
            )

    def _reply(self, command: Command) -> float | Answer:
        """Execute one parsed command: its value if it succeeded (no object built, as the
        loop's hot path wants), else a NaN :class:`Answer` saying why."""
        device = self._working.get(command.device)
        if device is None or command.error is not None:
            return self._refuse(command)
        try:
            value = float(device.simulate(command.value, self))
        except CommandError as exc:
            text = printable(command.text)
            return Answer.nan(logging.WARNING, f"bad command '{text}': {printable(str(exc))}")
        except DEVICE_FAULTS as exc:
            self._switch_off(device, f"command {command.text!r}", exc)
            text = printable(command.text)
            why = f"command '{text}': device {command.device} raised and is switched off"
            return Answer.nan(logging.DEBUG, why)
        widest = self._widest
        if -widest <= value <= widest and command.device not in self._robot.drives:
            return value  # a reading that fits the reply: the loop's common case
        if command.device in self._robot.drives:
            if math.isnan(value):
                why = f"'{printable(command.text)}': a drive is still moving"
                return Answer.nan(logging.DEBUG, why)
            self._start_move(self._robot.drives[command.device], command.text)
        if abs(value) > widest and math.isfinite(value):
            why = (
                f"command '{printable(command.text)}': device {command.device} read {value:g}, "
                f"beyond what a 4-byte reply holds (±{FLOAT32_MAX:.3g}); reply_bytes = 8 sends it"
            )
            return Answer.nan(logging.WARNING, why)
        return value

    def _refuse(self, command: Command) -> float | Answer:
        """A command no working device runs: malformed, the stop, or to a device switched off
        or not on the robot."""
        if command.error is not None:
            text = printable(command.text)
            return Answer.nan(logging.WARNING, f"bad command '{text}': {printable(command.error)}")
        if command.device == STOP_ID:
            self._robot.stop()
            self._end_move()
            return math.inf
        if command.device in self._switched_off:
            why = f"command '{printable(command.text)}': device {command.device} is switched off"
            return Answer.nan(logging.DEBUG, why)
        text = printable(command.text)
        why = f"bad command '{text}': no device '{printable(command.device)}' on the robot"
        return Answer.nan(logging.WARNING, why)

    # ----------------------------------------------------------------- time

    def step(self, n: int = 1) -> None:
        """Advance the simulation by ``n`` steps of ``1 / frame_rate`` seconds."""
        if self._owner is not None:
            self._check_thread("step")
        for _ in range(n):
            self._step_once()

    def own(self, thread: int | None) -> None:
        """Let only ``thread`` (an ident, the loop's: :meth:`simmer.runner.Runner.run`) drive
        the simulation; None: any thread may again. While owned, :meth:`command`, :meth:`step`
        and :meth:`reset` from another thread raise :class:`~simmer.errors.WrongThread`
        instead of racing the loop."""
        self._owner = thread

    def _check_thread(self, what: str) -> None:
        here = threading.get_ident()
        if here != self._owner:
            raise WrongThread(
                f"Simulation.{what}() was called from thread {threading.current_thread().name!r}"
                ", but the simulation belongs to the thread running its loop: hand it the "
                "message through the runner's bus (CommandBus.submit) instead"
            )

    def run_until_idle(self, max_seconds: float = 600.0) -> bool:
        """Step until no drive moves; False if one still moves after ``max_seconds`` simulated."""
        if self._owner is not None:
            self._check_thread("run_until_idle")
        limit = self._time + max_seconds
        robot = self._robot
        while robot.any_drive_moving:
            if self._time >= limit:
                return False
            self._step_once()
        return True

    def _step_once(self) -> None:
        robot = self._robot
        dt = self._dt
        dx = dy = rotation = used = 0.0
        moved = False
        robot.turned = 0.0
        robot.moved = STILL
        if self.manual_keys:
            dx, dy, rotation = self._manual_motion(dt)
            moved = True
        else:
            for drive in robot.drives.values():
                if drive.remaining != 0.0:
                    motion = drive.advance(dt)
                    dx += motion.dx
                    dy += motion.dy
                    rotation += motion.rotation
                    used += abs(motion.step)
                    moved = True
        moving = self._moving
        if moved:
            blocked = self._move(dx, dy, rotation)
            if moving is not None:
                if blocked:
                    moving.blocked += 1
                else:
                    moving.done += used
        self._time = (self.steps + 1) * dt
        self.steps += 1
        if moving is not None and not robot.any_drive_moving:
            self._end_move()  # said at the step its motion ran out
        # A try costs nothing until it catches (Python >= 3.11), and switching a device off
        # builds new lists, so these loops go on over the old ones.
        for device in self._updating:
            try:
                device.update(self)
            except DEVICE_FAULTS as exc:
                self._switch_off(device, "update()", exc)
        for device in self._listed:
            try:
                device.simulate(0.0, self)
            except CommandError as exc:
                self._unlist(device, exc)
            except DEVICE_FAULTS as exc:
                self._switch_off(device, "simulate() for simulate_list", exc)
        if self.observers:
            self.emit(StepEvent(self._time, robot.pose, self.steps))

    # ----------------------------------------------------------------- faulty devices

    def _switch_off(self, device: Device, during: str, exc: BaseException) -> None:
        """A device's own code raised: log it once and leave the device out until reset.

        Its commands then answer NaN and its update, simulate_list call and shapes are
        skipped, so one faulty device (typically a student's plug-in) never stops the run.
        """
        reason = describe_exception(exc)
        self._switched_off[device.id] = reason
        self._working.pop(device.id, None)
        self._updating = [d for d in self._updating if d is not device]
        self._listed = [d for d in self._listed if d is not device]
        log.error(
            "device %s (kind %r, class %s) raised in %s and is switched off until reset "
            "(its commands answer NaN): %s",
            device.id,
            device.kind,
            type(device).__name__,
            during,
            reason,
            exc_info=exc,
        )

    def _unlist(self, sensor: Device, exc: CommandError) -> None:
        """A simulate_list sensor refused a plain read: stop reading it every step (said once);
        commands to it still work."""
        self._listed = [d for d in self._listed if d is not sensor]
        log.warning("simulate_list: %s is no longer read every step: %s", sensor.id, exc)

    def shapes(self) -> list[Shape]:
        """Every device's latest measurement to draw; a device whose ``shapes`` raises is
        switched off."""
        shapes: list[Shape] = []
        off = self._switched_off
        for device in self._robot.devices.values():
            if device.id in off:
                continue
            try:
                shapes += device.shapes(self)
            except DEVICE_FAULTS as exc:
                self._switch_off(device, "shapes()", exc)
        return shapes

    def _start_move(self, drive: Drive, text: str) -> None:
        """A drive command was accepted: follow how far it gets (a zero move is none)."""
        self._end_move()
        if drive.remaining != 0.0:
            unit = "deg" if drive.rotational else "in"
            self._moving = _Move(printable(text.strip()), self._time, abs(drive.remaining), unit)

    def blocked_now(self, linger: float = BLOCKED_SHOWN) -> str | None:
        """What the window shows of a blocked move: the drive command moving now if a wall or
        the block has stopped any of its steps, else the last blocked move for ``linger``
        simulated seconds after it ended; None otherwise."""
        moving = self._moving
        if moving is not None and moving.blocked:
            return (
                f"blocked: '{moving.command}' {moving.blocked} steps, "
                f"got {moving.done:.1f} of {moving.amount:g} {moving.unit}"
            )
        last = self.last_blocked
        if last is not None and self._time - last.time <= linger:
            return (
                f"blocked: '{last.command}' {last.blocked_steps} steps, "
                f"got {last.done:.1f} of {last.amount:g} {last.unit}"
            )
        return None

    def _end_move(self) -> None:
        """The drive command moving now is done (or stopped): if a wall or the block stopped
        any of its steps, count it, log it and emit a :class:`BlockedMoveEvent`."""
        moving, self._moving = self._moving, None
        if moving is None or not moving.blocked:
            return
        self.blocked_moves += 1
        event = BlockedMoveEvent(
            self._time,
            moving.command,
            moving.started,
            moving.blocked,
            moving.done,
            moving.amount,
            moving.unit,
            self.steps,
        )
        self.last_blocked = event
        if self.blocked_moves <= MAX_BLOCKED_LOGGED:
            log.info("blocked move: %s", event.describe())
        if self.blocked_moves == MAX_BLOCKED_LOGGED:
            log.info(
                "%d blocked moves: the rest are counted in the outcome, not logged "
                "(MAX_BLOCKED_LOGGED)",
                MAX_BLOCKED_LOGGED,
            )
        if self.observers:
            self.emit(event)

    def _move(self, dx: float, dy: float, rotation: float) -> bool:
        """Apply a robot-frame motion unless it would touch a wall or the block (True: it
        would, and nothing moved)."""
        robot = self._robot
        pose = robot.pose
        rad = math.radians(pose.heading)  # geometry.rotate written out: no Vec2 built
        c, s = math.cos(rad), math.sin(rad)
        target = Pose(
            pose.x + (dx * c - dy * s),
            pose.y + (dx * s + dy * c),
            wrap_degrees(pose.heading + rotation),
        )
        if self._blocked(target):
            self.blocked_steps += 1
            if not self._was_blocked:
                self.collisions += 1
                self._was_blocked = True
                if self.observers:
                    self.emit(CollisionEvent(self._time, pose, self.steps))
            return True
        if self._was_blocked:
            self._was_blocked = False
            if self.observers:
                self.emit(CollisionEndEvent(self._time, target, self.steps))
        robot.pose = target
        robot.turned = rotation
        robot.moved = Vec2(dx, dy)
        block = self._block
        if block.held is not None:  # _blocked placed its outline at the target
            block.carry_to(block.carried_pose(target), self._carried)
        return False

    def _blocked(self, target: Pose) -> bool:
        """True if the robot at ``target`` would touch a wall or the block, or the block it
        holds would touch a wall."""
        robot = self._robot
        maze = self.maze
        block = self._block
        if block.held is None:
            return robot_blocked(
                robot.outline,
                target.x,
                target.y,
                target.heading,
                robot.scratch,
                maze.hwall,
                maze.vwall,
                maze.solid,
                maze.cell,
                block.polygon,
            )
        place_polygon(robot.outline, target.x, target.y, target.heading, robot.scratch)
        if polygon_hits_grid(robot.scratch, maze.hwall, maze.vwall, maze.solid, maze.cell):
            return True
        carried = block.carried_pose(target)
        place_polygon(block.local, carried.x, carried.y, carried.heading, self._carried)
        return polygon_hits_grid(self._carried, maze.hwall, maze.vwall, maze.solid, maze.cell)

    # ----------------------------------------------------------------- manual control

    def set_manual_keys(self, keys: Iterable[str]) -> None:
        """Hold these manual-driving keys (subset of ``wasdqe``) until the next call.

        w/s forward/back, q/e sideways toward robot +x/-x, d/a turn clockwise/anticlockwise, at
        6 in/s and 120 deg/s, never noisy, odometers untouched; commanded motion pauses.
        """
        held = frozenset(k.lower() for k in keys)
        unknown = held - set(MANUAL_KEYS)
        if unknown:
            raise ValueError(f"manual keys are {MANUAL_KEYS}, not {''.join(sorted(unknown))}")
        if held != self.manual_keys and self.observers:
            self.emit(KeysEvent(self._time, held, self.steps))
        self.manual_keys = held

    def _manual_motion(self, dt: float) -> tuple[float, float, float]:
        keys = self.manual_keys
        step = MANUAL_SPEED * dt
        turn = MANUAL_TURN * dt
        dy = step * (("w" in keys) - ("s" in keys))
        dx = step * (("q" in keys) - ("e" in keys))
        rotation = turn * (("d" in keys) - ("a" in keys))
        return dx, dy, rotation

    def place_robot(self, x: float, y: float, heading: float) -> bool:
        """Move the robot to a pose if it fits there (no wall, block or outside); True if moved."""
        robot = self._robot
        pose = Pose(x, y, wrap_degrees(heading))
        if self._blocked(pose):
            return False
        robot.pose = pose
        if self._block.held is not None:  # _blocked placed its outline at the pose
            self._block.carry_to(self._block.carried_pose(pose), self._carried)
        if self.observers:
            self.emit(PlaceEvent(self._time, robot.pose, self.steps))
        return True

    # ----------------------------------------------------------------- lifecycle

    def reset(self, seed: int | None = None) -> None:
        """Put robot, block, devices, time and the random generator back to the start, as a
        new simulation of this configuration starts (observers stay). With ``seed``, the
        noise comes from that seed from now on: a sweep's worker runs seed after seed on one
        simulation this way, without building the maze and devices' settings again. (The
        reset's event does not carry the seed: change it before recording, not during.)"""
        if self._owner is not None:
            self._check_thread("reset")
        time, step = self._time, self.steps  # the event says when it was asked for
        if seed is not None:
            self.seed = seed
        self._build()
        if self.observers:
            self.emit(ResetEvent(time, step))

    def expected(
        self, poses: Any, sensors: Sequence[str] | None = None, *, block: bool = True
    ) -> FloatArray:
        """Noise-free readings of ``sensors`` at many robot poses ((N, 3): x, y, heading),
        with the simulator's own geometry: (N, S), for ultrasonic, infrared, compass and
        time-of-flight sensors; ``block=False`` sees the walls only."""
        from simmer.world.expected import expected

        return expected(self, poses, sensors, block=block)

    def lidar_table(self, step: float, sensor: str) -> tuple[FloatArray, FloatArray, FloatArray]:
        """LiDAR ``sensor``'s noise-free scans from the walls alone, its centre every ``step``
        inches, facing heading 0: (xs, ys, readings[y, x, beam]); facing heading h it reads
        the same scan rotated (``np.roll(scan, -round(h * beams / 360))``)."""
        from simmer.world.expected import lidar_table

        return lidar_table(self, step, sensor)

    def add_observer(self, observer: Observer) -> None:
        """Call ``observer(event)`` for every event of the run (see :mod:`simmer.world.events`)."""
        self.observers.append(observer)

    def remove_observer(self, observer: Observer) -> None:
        """Stop calling ``observer`` (no error if it was not added)."""
        if observer in self.observers:
            self.observers.remove(observer)

    def emit(self, event: Event) -> None:
        """Give ``event`` to every observer (the loop around the simulation adds its own)."""
        for observer in self.observers:
            observer(event)
