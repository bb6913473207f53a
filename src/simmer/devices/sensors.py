"""The four built-in sensor kinds: ultrasonic, gyroscope, compass, infrared (BEHAVIOUR §5.3-5.6)."""

from __future__ import annotations

import math
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from simmer.devices.base import (
    BlockView,
    Circle,
    Color,
    Device,
    DeviceParams,
    MazeView,
    Segment,
    Shape,
    Whole,
    World,
)
from simmer.geometry import (
    FloatArray,
    Pose,
    Vec2,
    cast_fans,
    disk_samples,
    heading_vector,
    rectangle,
    white_fraction,
    wrap_degrees,
)

# ----------------------------------------------------------------------------- ultrasonic


class MeasuredParams(DeviceParams):
    """Settings of a sensor whose latest measurement the window can draw."""

    visible_measurement: bool = Field(True, description="Draw the measurement after a read.")
    visible_measurement_time: float = Field(0.5, ge=0, description="How long, in seconds.")


class UltrasonicParams(MeasuredParams):
    """Ultrasonic range finder settings (defaults as SimMeR's)."""

    type: str = "ultrasonic"
    height: float | None = Field(
        None, gt=0, description="Mounting height in inches; defaults to the block size."
    )
    beamwidth: float = Field(
        15.0, ge=0, lt=180, description="Cone angle in degrees (0 only in an original config.py)."
    )
    num_rays: Whole = Field(7, ge=1, le=1000, description="Rays cast across the cone.")
    min_range: float = Field(0.0, ge=0, description="Shortest reading, inches.")
    max_range: float = Field(433.0, gt=0, description="Longest reading, inches.")
    error: float = Field(0.02, ge=0, description="Percent error (SimMeR's, sd 2·error).")
    ray_color: Color = Field((0, 255, 0), description="RGB colour of the drawn rays.")

    def problems(self) -> list[tuple[str, str]]:
        """Cross-field mistakes, as (key, message) pairs."""
        if self.max_range <= self.min_range:
            return [
                (
                    "max_range",
                    f"must be greater than min_range ({self.min_range:g}), got {self.max_range:g}",
                )
            ]
        return []

    def strict_problems(self) -> list[tuple[str, str]]:
        """``beamwidth = 0``, which the original ran as a single ray, as a (key, message) pair."""
        if self.beamwidth == 0.0:
            return [
                (
                    "beamwidth",
                    "must be greater than 0; a beamwidth of 0 sends every ray along the "
                    "sensor's heading, so it reads like a single ray: for that, set "
                    "num_rays = 1 (with any beamwidth)",
                )
            ]
        return []


class _Fans:
    """A robot's ultrasonic sensors cast together, once a pose: a message reads several
    (``u0,u1,u2,u3``), and one compiled call for all of them costs less than one call each
    (:func:`~simmer.geometry.cast_fans`). A program that reads one sensor a pose would pay
    for every fan, so a pose casts every fan only when more than one was read at the pose
    before; otherwise each fan when it is first read. A sensor of a subclass of
    :class:`Ultrasonic` is cast on its own, from its attributes as they are at each cast (it
    may turn itself).

    A cast holds while the robot's pose, the block's outline and the maze are the very objects
    it was made for: the robot moves by a new pose, and the block by a new outline
    (:meth:`~simmer.config.maze.Block.place`) or with the robot it is carried by."""

    def __init__(self, sensors: list[Ultrasonic], fixed: bool) -> None:
        self.sensors = [] if fixed else sensors
        """The sensors whose mounts are read again at each cast (a subclass's: one)."""
        self.mounts = self._mounts(sensors)
        self.columns = 4 + int(self.mounts[:, 6].max())
        self.latest: FloatArray = np.zeros((len(sensors), self.columns))
        """The latest cast, a row a sensor: its x, y and heading in the world, its fan's
        shortest distance, then each ray's (inf: nothing within range). A new array a pose:
        each sensor's last read keeps the rays it measured, for the window."""
        self.distances = [math.inf] * len(sensors)
        self.cast = [False] * len(sensors)
        """Whether each sensor's fan is cast at this pose (its row of :attr:`latest` and its
        distance hold)."""
        self.pose: Pose | None = None
        self.block: FloatArray | None = None
        self.maze: MazeView | None = None

    @staticmethod
    def _mounts(sensors: list[Ultrasonic]) -> FloatArray:
        rows = []
        for sensor in sensors:
            s = sensor.settings
            height = math.nan if sensor._height is None else sensor._height
            x, y = sensor.position
            rows.append((x, y, sensor.rotation, height, s.beamwidth, s.max_range, s.num_rays))
        return np.array(rows, dtype=np.float64)

    def distance(self, slot: int, robot_pose: Pose, block: BlockView, maze: MazeView) -> float:
        """Sensor ``slot``'s noise-free distance (inf: nothing within its range), cast first
        if it is not at this pose yet."""
        if robot_pose is not self.pose or block.segments is not self.block or maze is not self.maze:
            every = self.cast.count(True) > 1  # as many read at the pose before
            self.latest = np.empty((len(self.mounts), self.columns))
            self.cast = [every] * len(self.mounts)
            self._fill(robot_pose, block, maze, -1 if every else slot)
            # a sensor whose mount may change is cast again at each read
            self.pose = None if self.sensors else robot_pose
            self.block, self.maze = block.segments, maze
        elif not self.cast[slot]:
            self._fill(robot_pose, block, maze, slot)
        return self.distances[slot]

    def _fill(self, robot_pose: Pose, block: BlockView, maze: MazeView, only: int) -> None:
        """Cast sensor ``only``'s fan (-1: every one) into :attr:`latest`."""
        if self.sensors:
            self.mounts = self._mounts(self.sensors)
        rx, ry, rheading = robot_pose
        cast = self.latest
        cast_fans(
            maze.hwall,
            maze.vwall,
            maze.cell,
            maze.segments,
            block.segments,
            rx,
            ry,
            rheading,
            block.x,
            block.y,
            block.size,
            self.mounts,
            cast,
            only,
        )
        if only < 0:
            self.distances = cast[:, 3].tolist()
        else:
            self.distances[only] = float(cast[only, 3])
            self.cast[only] = True


class Ultrasonic(Device):
    """Shortest distance at which any ray of the cone meets a wall (or the block, if seen)."""

    Params = UltrasonicParams
    block_noise: ClassVar[bool] = True
    default_outline: ClassVar[FloatArray] = rectangle(2.0, 1.0)

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, UltrasonicParams)
        self.settings = params
        self.last_time = -math.inf
        self.reading = math.nan
        # the mounting height if set (None: the block's size, read at each read)
        self._height = params.height if params.height is not None else self.mount_height
        self._fans: _Fans | None = None
        """The robot's sensors cast with this one (made at the first read)."""
        self._slot = 0
        """This sensor's row in them."""
        before = np.concatenate((np.zeros(4), np.full(params.num_rays, math.inf)))
        self._seen: FloatArray = before.reshape(1, -1)
        """The cast of its last read (:attr:`_Fans.latest`, whose row :attr:`_seen_slot` is
        this sensor's: kept as they are, nothing built a read): drawn."""
        self._seen_slot = 0

    def height(self, world: World) -> float:
        """Mounting height: ``height``, else the third position value, else the block size."""
        return world.block.size if self._height is None else self._height

    def sees_block(self, world: World, x: float, y: float) -> bool:
        """Block visibility: ``atan(h / d) <= beamwidth / 2`` (BEHAVIOUR §5.3)."""
        block = world.block
        h = self.height(world) - block.size
        d = math.hypot(block.x - x, block.y - y)
        return math.degrees(math.atan2(h, d)) <= self.settings.beamwidth / 2.0

    def _join(self, world: World) -> _Fans:
        """Cast with the robot's other ultrasonic sensors of this very kind that have no
        company yet (a subclass's sensor: alone)."""
        mates = [
            d for d in world.robot.devices.values() if type(d) is Ultrasonic and d._fans is None
        ]
        fixed = type(self) is Ultrasonic and any(d is self for d in mates)
        if not fixed:
            mates = [self]
        fans = _Fans(mates, fixed)
        for slot, sensor in enumerate(mates):
            sensor._fans, sensor._slot = fans, slot
        return fans

    def simulate(self, value: float, world: World) -> float:
        """Measure the distance in inches, with noise, clamped to [min_range, max_range]."""
        fans = self._fans or self._join(world)
        distance = fans.distance(self._slot, world.robot.pose, world.block, world.maze)
        s = self.settings
        if distance == math.inf:
            reading = s.max_range
        else:
            error = s.error
            if error != 0.0 and distance != 0.0:  # percent_error written out
                distance += self.gauss() * error * distance
            reading = min(max(distance, s.min_range), s.max_range)
        self.last_time = world.time
        self._seen, self._seen_slot = fans.latest, self._slot
        self.reading = reading
        return reading

    @property
    def rays(self) -> FloatArray:
        """Each ray's distance at the last read (inf: nothing within range)."""
        return self._seen[self._seen_slot, 4 : 4 + self.settings.num_rays]

    @property
    def last_heading(self) -> float:
        """Which way the sensor faced at its last read, degrees."""
        return float(self._seen[self._seen_slot, 2])

    @property
    def last_origin(self) -> Vec2:
        """Where the sensor was at its last read (built when the window asks)."""
        row = self._seen[self._seen_slot]
        return Vec2(float(row[0]), float(row[1]))

    def shapes(self, world: World) -> list[Shape]:
        """The rays of the last read, while it is recent enough to show."""
        s = self.settings
        if not s.visible_measurement or world.time - self.last_time > s.visible_measurement_time:
            return []
        n = s.num_rays
        rays, origin, heading = self.rays, self.last_origin, self.last_heading
        out: list[Shape] = []
        for k in range(n):
            length = min(float(rays[k]), s.max_range)
            direction = heading_vector(heading + ((k - (n - 1) / 2.0) / n) * s.beamwidth)
            end = Vec2(origin.x + direction.x * length, origin.y + direction.y * length)
            out.append(Segment(origin, end, s.ray_color))
        return out


# ----------------------------------------------------------------------------- gyroscope


class GyroscopeParams(DeviceParams):
    """Gyroscope settings."""

    type: str = "gyroscope"
    bias: float = Field(0.1, description="Drift in degrees per second.")
    error: float = Field(0.2, ge=0, description="Percent error on each step's change.")


class Gyroscope(Device):
    """Integrates the heading change each step, with drift and noise; wraps to [0, 360)."""

    Params = GyroscopeParams
    block_noise: ClassVar[bool] = True

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, GyroscopeParams)
        self.settings = params
        self.angle = 0.0

    def update(self, world: World) -> None:
        """Add this step's true heading change plus drift, with percent error."""
        change = world.robot.turned + self.settings.bias * world.dt
        error = self.settings.error
        if error != 0.0 and change != 0.0:  # percent_error written out (once a step)
            change += self.gauss() * error * change
        self.angle = wrap_degrees(self.angle + change)

    def simulate(self, value: float, world: World) -> float:
        """The accumulated angle since the start, in [0, 360)."""
        return self.angle


# ----------------------------------------------------------------------------- compass


class CompassParams(DeviceParams):
    """Compass settings."""

    type: str = "compass"
    bias: float = Field(0.0, description="Constant offset in degrees.")
    error: float = Field(
        0.002, ge=0, description="Noise: standard deviation 2·error·360 degrees (SimMeR's)."
    )


class Compass(Device):
    """The absolute heading (angle from +y) plus bias and noise, in [0, 360)."""

    Params = CompassParams
    block_noise: ClassVar[bool] = True

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, CompassParams)
        self.settings = params

    def simulate(self, value: float, world: World) -> float:
        """Heading in degrees, with noise."""
        s = self.settings
        heading = world.robot.pose.heading + self.rotation + s.bias
        if s.error:
            heading += self.gauss() * s.error * 360.0
        return wrap_degrees(heading)


# ----------------------------------------------------------------------------- infrared

_DISK = disk_samples(256)


class InfraredParams(MeasuredParams):
    """Downward infrared floor sensor settings."""

    type: str = "infrared"
    height: float = Field(3.0, gt=0, description="Height above the floor, inches.")
    fov: float = Field(60.0, gt=0, lt=180, description="Field of view, degrees.")
    error: float = Field(0.02, ge=0, description="Percent error on the white fraction.")
    threshold: float = Field(0.8, ge=0, le=1, description="White fraction that reads 1.")
    radius_model: Literal["geometric", "simmer"] = Field(
        "geometric",
        description="'geometric': radius height·tan(fov/2); 'simmer': the original's "
        "height·cos(fov/2).",
    )
    color: Color = Field((255, 128, 0), description="RGB colour of the outline and black reads.")


class Infrared(Device):
    """Reads 1 when at least ``threshold`` of the floor circle below it is white, else 0."""

    Params = InfraredParams
    block_noise: ClassVar[bool] = True
    default_outline: ClassVar[FloatArray] = rectangle(0.6, 0.6)

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, InfraredParams)
        self.settings = params
        half_fov = math.radians(params.fov / 2.0)
        trig = math.tan if params.radius_model == "geometric" else math.cos
        height = params.height
        if "height" not in params.model_fields_set and self.mount_height is not None:
            height = self.mount_height  # [x, y, height] given instead of `height`
        self.radius = height * trig(half_fov)
        self.last_time = -math.inf
        self._center_x = self._center_y = 0.0
        self.reading = math.nan

    def white_fraction(self, world: World) -> float:
        """Exact-to-1/256 fraction of the sensed floor circle that is white (no noise)."""
        rx, ry, rheading = world.robot.pose  # world_pose written out: no Pose built
        px, py = self.position
        rad = math.radians(rheading)
        c, sn = math.cos(rad), math.sin(rad)
        x = rx + px * c - py * sn
        y = ry + px * sn + py * c
        maze = world.maze
        self._center_x, self._center_y = x, y
        return float(white_fraction(maze.floor_white, maze.tile, x, y, self.radius, _DISK))

    @property
    def last_center(self) -> Vec2:
        """The centre of the floor circle at the last read (built when the window asks)."""
        return Vec2(self._center_x, self._center_y)

    def simulate(self, value: float, world: World) -> float:
        """1.0 (white) or 0.0 (black)."""
        s = self.settings
        fraction = min(max(self.percent_error(self.white_fraction(world), s.error), 0.0), 1.0)
        self.last_time = world.time
        self.reading = 1.0 if fraction >= s.threshold else 0.0
        return self.reading

    def shapes(self, world: World) -> list[Shape]:
        """The sensed circle of the last read, while recent."""
        s = self.settings
        if not s.visible_measurement or world.time - self.last_time > s.visible_measurement_time:
            return []
        color = (0, 200, 0) if self.reading == 1.0 else s.color
        return [Circle(self.last_center, self.radius, color)]
