"""The ``lidar`` kind: a spinning 2D laser scanner modelled on the Slamtec RPLidar A1M8.

Datasheet figures used (RPLidar A1M8, Slamtec LD108): a 360 degree scan, 5.5 revolutions a
second by default (2 to 10 Hz as the motor is driven), about 2,000 samples a second, so about
one degree between samples at 5.5 Hz; range 0.15 to 12 m (5.9 to 472 in); distance
resolution below 1% of the range. The defaults below follow them.

A scan takes one revolution of simulated time: beam k of a revolution that starts at ``t0``
is measured at ``t0 + k / (beams · scan_rate)``, from where the robot is then (the poses of
the steps around it, interpolated), so a turning robot's scan is smeared as the real one's
is (``motion_skew``; off: the whole scan from the pose at its end). A read answers from the
latest complete scan; before the first revolution ends that is the scan the spinning LiDAR
made at the start pose before the run began.

Noise, each from the device's own seeded stream and drawn in a fixed order per scan:
``range_error + range_error_proportional · d`` inches standard deviation on a distance ``d``
(Stage's ranger model), ``angular_jitter`` degrees standard deviation on each beam's true
direction (the angle reported stays the nominal one), and ``dropout``, the chance a beam
returns nothing. A beam with no return (nothing within ``max_range``, closer than
``min_range``, or dropped) reads 0, as the RPLidar reports an invalid measurement (distance
0, quality 0).

Reads (docs/protocol.md): ``l0-A`` (0 <= A < 360) the distance in inches of the beam nearest
A degrees clockwise from the LiDAR's front; ``l0--1`` the beams per revolution; ``l0--2``
the number of the scan answering (it grows by one a revolution), so one message reads a
whole scan consistently: ``simmer.client.Client.scan``.
"""

from __future__ import annotations

import bisect
import math
from typing import ClassVar

import numpy as np
from pydantic import Field

from simmer.devices.base import Circle, Color, Device, DeviceParams, Shape, Whole, World
from simmer.devices.sensors import MeasuredParams
from simmer.errors import CommandError
from simmer.geometry import FloatArray, Vec2, rectangle, scan_revolution

MAX_BEAMS = 999
"""Most beams per revolution: a whole scan is read in one message of a command per beam plus
the scan number, within the protocol's 1,000 commands (``MAX_COMMANDS``)."""
BEAMS_READ = -1.0
"""``l0--1``: the beams per revolution."""
SCAN_NUMBER_READ = -2.0
"""``l0--2``: the number of the scan that answers."""


class LidarParams(MeasuredParams):
    """A 2D scanning LiDAR's settings (defaults: the RPLidar A1M8's datasheet)."""

    type: str = "lidar"
    height: float | None = Field(
        None,
        gt=0,
        description="Height of the scan plane, inches; defaults to the third position value, "
        "else the robot's height (on top). Below the block's top it sees the block.",
    )
    beams: Whole = Field(360, ge=1, description="Beams per revolution (999 at most, MAX_BEAMS).")
    scan_rate: float = Field(5.5, gt=0, le=100, description="Revolutions per second.")
    min_range: float = Field(5.9, ge=0, description="Shortest distance it measures, inches.")
    max_range: float = Field(472.0, gt=0, description="Longest distance it measures, inches.")
    range_error: float = Field(
        0.02, ge=0, description="Constant part of the distance noise's sd, inches."
    )
    range_error_proportional: float = Field(
        0.01, ge=0, description="Part of the distance noise's sd proportional to the distance."
    )
    angular_jitter: float = Field(
        0.1, ge=0, description="Sd of each beam's true direction about the reported one, degrees."
    )
    dropout: float = Field(0.01, ge=0, le=1, description="Chance that a beam returns nothing.")
    motion_skew: bool = Field(
        True, description="Take a scan over one revolution of simulated time (False: at once)."
    )
    point_color: Color = Field((220, 0, 220), description="RGB colour of the drawn points.")

    def problems(self) -> list[tuple[str, str]]:
        """``max_range`` not above ``min_range``, or too many beams, as (key, message) pairs."""
        found = []
        if self.max_range <= self.min_range:
            found.append(
                (
                    "max_range",
                    f"must be greater than min_range ({self.min_range:g}), got {self.max_range:g}",
                )
            )
        if self.beams > MAX_BEAMS:
            found.append(
                (
                    "beams",
                    f"must be at most {MAX_BEAMS} (MAX_BEAMS), got {self.beams}: a whole scan is "
                    "read in one message of at most 1,000 commands",
                )
            )
        return found

    def noise_keys(self) -> list[str]:
        """The noise settings in effect that are not zero (``simmer check``'s summary)."""
        names = ("range_error", "range_error_proportional", "angular_jitter", "dropout")
        return [name for name in names if getattr(self, name)]


class Lidar(Device):
    """A spinning 2D LiDAR modelled on the RPLidar A1M8, a whole scan a revolution: ``l0-A``
    reads the beam at A degrees (0: none returned), ``l0--1`` the beams, ``l0--2`` the scan's
    number (docs/protocol.md)."""

    Params = LidarParams
    default_outline: ClassVar[FloatArray] = rectangle(2.8, 3.8)

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, LidarParams)
        self.settings = params
        n = params.beams
        self.period = 1.0 / params.scan_rate
        self.directions: FloatArray = np.arange(n, dtype=np.float64) * (360.0 / n)
        """Each beam's nominal angle, degrees clockwise from the LiDAR's front."""
        self.mount = np.array([self.position.x, self.position.y, self.rotation])
        self.distances: FloatArray = np.zeros(n)
        """The latest scan's readings, inches (0: no return)."""
        self.points: FloatArray = np.full((n, 2), math.nan)
        """Where each beam of the latest scan met something, world inches (NaN: no return)."""
        self.number = 0
        """The latest scan's number: 1 the one made at the start pose, then one a revolution."""
        self.scan_time = 0.0
        """When the latest scan ended, simulated seconds."""
        self._times: list[float] = []
        """When each pose of ``_poses`` was recorded: the revolution under way's steps."""
        self._poses: list[float] = []
        """The robot's poses at ``_times``, flat (x, y, heading unwrapped, x, ...): a list
        appended to each step and made an array once a scan, the cheapest way per step."""
        self._true = np.empty(n)
        self._beam_poses = np.empty((n, 3))
        self._noise = np.zeros((3, n))
        """Each scan's draws: beams' direction and range errors in standard deviations, and
        uniform draws against the dropout chance (rows left 0 when their noise is off)."""
        jitter, ranged = (
            params.angular_jitter,
            params.range_error or params.range_error_proportional,
        )
        rows = slice(0 if jitter else 1, 2 if ranged else 1)
        self._normals = self._noise[rows] if rows.start < rows.stop else None
        """The rows of ``_noise`` drawn as standard normals, in one call (the stream's order
        as drawing each row alone)."""
        self._uniforms = self._noise[2] if params.dropout else None
        self._offsets = self.period * (np.arange(n) / n)
        """When each beam is measured after its revolution starts, seconds."""
        self._limits = np.array(
            [
                params.min_range,
                params.max_range,
                params.range_error,
                params.range_error_proportional,
                params.dropout,
                params.angular_jitter,
            ]
        )
        self._due = self.period - 1e-9
        """When the revolution under way ends (a hair early: steps' times are sums)."""
        self._heading = 0.0
        """The heading of the latest pose recorded, as the robot has it (in [0, 360))."""

    def height(self, world: World) -> float:
        """The scan plane's height: ``height``, else the third position value, else the
        robot's height."""
        if self.settings.height is not None:
            return self.settings.height
        return self.mount_height if self.mount_height is not None else world.robot.height

    def sees_block(self, world: World) -> bool:
        """A scan plane below the block's top meets the block."""
        return self.height(world) < world.block.size

    # -- stepping ------------------------------------------------------------------------

    def _record(self, world: World) -> float:
        """Keep the robot's pose now (its heading unwrapped from the last one's), and the
        first scan (at the start pose) if none is made yet; the time now. Called every step:
        kept lean (a step without a scan costs the LiDAR a few tenths of a microsecond)."""
        now = world.time
        times = self._times
        if not times:
            self._first(world)
        if now <= times[-1]:
            return now
        pose = world.robot.pose
        heading = pose.heading
        poses = self._poses
        last = poses[-1]
        times.append(now)
        if -180.0 < last - heading < 180.0:  # within a half turn of the last: as it is
            poses.extend(pose)
        else:
            poses += (pose.x, pose.y, heading + 360.0 * round((last - heading) / 360.0))
        self._heading = heading
        return now

    def _first(self, world: World) -> None:
        """The first pose recorded and the scan the spinning LiDAR made there before the run
        began (the start pose's, if the run has begun)."""
        start = world.robot.start_pose if world.time > 0.0 else world.robot.pose
        self._times.append(0.0)
        self._poses += (start.x, start.y, start.heading)
        self._heading = start.heading
        self._scan(world, 0.0, skew=False)

    def update(self, world: World) -> None:
        """Record this step's pose; cast every scan whose revolution has ended."""
        now = self._record(world)
        if now < self._due:
            return
        while now >= self._due:
            self._scan(world, self.scan_time + self.period, skew=self.settings.motion_skew)
        # drop the poses before the revolution under way (the one before it stays)
        keep = bisect.bisect_right(self._times, self.scan_time) - 1
        if keep > 0:
            del self._times[:keep], self._poses[: 3 * keep]

    def _scan(self, world: World, end: float, *, skew: bool) -> None:
        """Cast the revolution ending at ``end`` and draw its noise (see the module doc)."""
        noise = self._noise
        if self._normals is not None:
            self.rng.standard_normal(out=self._normals)
        if self._uniforms is not None:
            self.rng.random(out=self._uniforms)
        maze = world.maze
        scan_revolution(
            maze.hwall,
            maze.vwall,
            maze.cell,
            maze.segments,
            world.block.segments,
            self.sees_block(world),
            np.array(self._times),
            np.array(self._poses).reshape(-1, 3),
            self._heading,
            end - self.period,
            end,
            skew,
            self._offsets,
            self.mount,
            self.directions,
            self._limits,
            noise,
            self._beam_poses,
            self._true,
            self.distances,
            self.points,
        )
        self.number += 1
        self.scan_time = end
        self._due = end + self.period - 1e-9

    # -- reading -------------------------------------------------------------------------

    def simulate(self, value: float, world: World) -> float:
        """A beam's distance of the latest scan (``value``: its angle, 0 to 360 degrees), or
        -1: the beams per revolution, -2: the scan's number."""
        self._record(world)
        if value == BEAMS_READ:
            return float(self.settings.beams)
        if value == SCAN_NUMBER_READ:
            return float(self.number)
        if not 0.0 <= value < 360.0:
            raise CommandError(
                f"a LiDAR reads the beam at an angle from 0 to 360 degrees, or -1 (the beams "
                f"per revolution) or -2 (the scan's number); {value:g} is none of them"
            )
        n = self.settings.beams
        return float(self.distances[round(value * n / 360.0) % n])

    def shapes(self, world: World) -> list[Shape]:
        """The latest scan's points, while recent enough to show."""
        s = self.settings
        if not s.visible_measurement or world.time - self.scan_time > s.visible_measurement_time:
            return []
        color = s.point_color
        return [
            Circle(Vec2(float(x), float(y)), 0.35, color)
            for x, y in self.points
            if not math.isnan(x)
        ]
