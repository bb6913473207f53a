"""Sensors of the robot's own motion: an MPU6050-like IMU (``imu``) and wheel encoders
(``encoder``). Both sense what the robot did in each step (:attr:`RobotView.turned` and
:attr:`RobotView.moved`), so a robot that is blocked, or placed by hand, senses no motion.

The IMU's noise is the usual continuous-time model (as Kalibr and ROS's IMU plug-ins give it):
a white noise of density ``N`` reads as standard deviation ``N / sqrt(dt)`` in one sample, and
a bias random walk of ``B`` moves the bias by ``B * sqrt(dt) * normal()`` every step. The
bias walk has its own stream, spawned from the device's, so how often a program reads never
changes how the bias wanders.
"""

from __future__ import annotations

import math
from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field

from simmer.devices.base import Device, DeviceParams, World
from simmer.errors import CommandError
from simmer.geometry import FloatArray, rectangle

G_IN_S2 = 386.0886
"""Standard gravity in inches per second squared."""

Pair = tuple[float, float]
NonNegativePair = tuple[
    Annotated[float, Field(ge=0)],
    Annotated[float, Field(ge=0)],
]

COUNT_SLACK = 1e-6
"""Counts an encoder's angle may fall short of a whole count and still reach it: the sum of
many steps' float arcs lands a hair below a whole count it reaches exactly."""

Step = tuple[float, float, float, float]
"""The robot's motion in one step: moved x and y (robot frame), degrees turned, the heading
after it."""
STANDING: Step = (0.0, 0.0, 0.0, 0.0)
"""A step before the first: the robot did not move."""

WALK_BLOCK = 1024
"""Steps of an IMU's bias walk drawn at once (and of an encoder's slip)."""

IMU_AXES = ("yaw rate", "x acceleration", "y acceleration")
"""What ``i0-0``, ``i0-1`` and ``i0-2`` read."""

# ----------------------------------------------------------------------------- IMU


class ImuParams(DeviceParams):
    """IMU settings; the defaults are the MPU6050's datasheet figures where it gives them."""

    type: str = "imu"
    gyro_noise_density: float = Field(
        0.005, ge=0, description="Yaw rate white noise, °/s/√Hz (MPU6050: 0.005)."
    )
    gyro_bias: float = Field(
        0.0, description="Yaw rate bias at the start, °/s (0: calibrated at start-up)."
    )
    gyro_bias_walk: float = Field(
        0.0005, ge=0, description="Yaw rate bias random walk, °/s per √s."
    )
    accel_noise_density: NonNegativePair = Field(
        (400e-6 * G_IN_S2, 400e-6 * G_IN_S2),
        description="[x, y] acceleration white noise, in/s²/√Hz (MPU6050: 400 µg/√Hz).",
    )
    accel_bias: Pair = Field(
        (0.0, 0.0), description="[x, y] acceleration bias at the start, in/s²."
    )
    accel_bias_walk: NonNegativePair = Field(
        (0.002, 0.002), description="[x, y] acceleration bias random walk, in/s² per √s."
    )

    def noise_keys(self) -> list[str]:
        """The noise settings that are not zero (``simmer check``'s summary)."""
        names = (
            "gyro_noise_density",
            "gyro_bias",
            "gyro_bias_walk",
            "accel_noise_density",
            "accel_bias",
            "accel_bias_walk",
        )
        return [name for name in names if np.any(np.asarray(getattr(self, name)) != 0)]


class Imu(Device):
    """Yaw rate and the two planar accelerations of its mounting point, with noise and bias.

    Axes are the chip's, lying flat: x toward the robot's right as the window shows it, y
    ahead, z up, turned by the device's ``rotation``. ``i0-0`` reads the yaw rate about z in
    °/s (positive anticlockwise in the window, so the opposite sign to the heading's change);
    ``i0-1`` and ``i0-2`` the acceleration along x and y in in/s² (gravity, along z, is left
    out). The mounting point's acceleration includes its turn about the robot's centre; it is
    the centred difference of the last two steps' velocities (the acceleration at the last
    step's start: one step behind, exact for a steady turn).
    """

    Params = ImuParams
    default_outline: ClassVar[FloatArray] = rectangle(0.8, 0.8)
    readings: ClassVar[tuple[str, ...]] = ("", "-1", "-2")

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, ImuParams)
        self.settings = params
        self.read_rng, self.walk_rng = rng.spawn(2)
        self.bias0 = (params.gyro_bias, *params.accel_bias)
        self.density = (params.gyro_noise_density, *params.accel_noise_density)
        self.walk = np.array([params.gyro_bias_walk, *params.accel_bias_walk], dtype=np.float64)
        self.walked = np.zeros((0, 3))
        """The bias walk over a block of steps: row k, its sum after the block's step k + 1."""
        self.walk_base = np.zeros(3)
        """The walk of the blocks before it."""
        self.walk_from = 0
        """The step the block starts after."""
        self.last: Step = STANDING
        """The robot's motion in the last step."""
        self.before_last: Step = STANDING
        """... and in the step before it."""
        rad = math.radians(self.rotation)
        self.turn = (math.cos(rad), math.sin(rad))
        """Cosine and sine of the device's rotation on the robot."""

    def update(self, world: World) -> None:
        """Keep this step's motion and the last one's (what a read needs, and all a step
        costs: the readings are worked out when they are read)."""
        robot = world.robot
        self.before_last = self.last
        self.last = (robot.moved.x, robot.moved.y, robot.turned, robot.pose.heading)

    def _velocity(self, step: Step, dt: float) -> tuple[float, float, float, float]:
        """The mounting point's world velocity in ``step`` (in/s), and the cosine and sine of
        the heading the step started from."""
        mx, my, turned, heading = step
        before = heading - turned
        cb, sb = math.cos(math.radians(before)), math.sin(math.radians(before))
        cn, sn = math.cos(math.radians(heading)), math.sin(math.radians(heading))
        px, py = self.position
        # the centre's displacement (robot frame at the step's start, rotated into the
        # world's) plus the mounting point's turn about the centre
        vx = (mx * cb - my * sb + px * (cn - cb) - py * (sn - sb)) / dt
        vy = (mx * sb + my * cb + px * (sn - sb) + py * (cn - cb)) / dt
        return vx, vy, cb, sb

    def true(self, axis: int, dt: float) -> float:
        """The noise-free reading of ``axis`` (chip axes) after the last step."""
        if axis == 0:  # z is up: anticlockwise in the window, the heading's opposite
            return -self.last[2] / dt
        if not (any(self.last[:3]) or any(self.before_last[:3])):
            return 0.0  # standing still: the usual case
        vx, vy, cb, sb = self._velocity(self.last, dt)
        ux, uy, _, _ = self._velocity(self.before_last, dt)
        ax, ay = (vx - ux) / dt, (vy - uy) / dt
        # a centred difference: the acceleration at the last step's start, so into the
        # device's frame as it was then (sim axes: x toward the robot's left in the window),
        # then the chip's (x to the right, so x changes sign)
        cr, sr = self.turn
        c = cb * cr - sb * sr  # cos and sin of -(before + rotation)
        s = -(sb * cr + cb * sr)
        return -(ax * c - ay * s) if axis == 1 else ax * s + ay * c

    def bias(self, axis: int, world: World) -> float:
        """The bias of ``axis`` now: the start's plus its walk over the steps so far, drawn
        :data:`WALK_BLOCK` steps at a time in one order, so the same whenever it is read."""
        bias = self.bias0[axis]
        if not self.walk.any():
            return bias
        dt = world.dt
        step = round(world.time / dt)
        while step > self.walk_from + len(self.walked):
            if len(self.walked):
                self.walk_base += self.walked[-1]
                self.walk_from += len(self.walked)
            draws = self.walk_rng.standard_normal((WALK_BLOCK, 3))
            self.walked = np.cumsum(draws * (self.walk * math.sqrt(dt)), axis=0)
        if step > self.walk_from:
            bias += float(self.walk_base[axis] + self.walked[step - self.walk_from - 1, axis])
        return bias

    def simulate(self, value: float, world: World) -> float:
        """Axis ``value`` (0 yaw rate, 1 x, 2 y) with its bias and white noise."""
        axis = int(value)
        if axis != value or not 0 <= axis <= 2:
            raise CommandError(
                f"{self.id} reads axis 0 ({IMU_AXES[0]}, °/s), 1 ({IMU_AXES[1]}) or 2 "
                f"({IMU_AXES[2]}, in/s²), not {value:g}"
            )
        reading = self.true(axis, world.dt) + self.bias(axis, world)
        density = self.density[axis]
        if density:
            reading += density / math.sqrt(world.dt) * float(self.read_rng.standard_normal())
        return reading


# ----------------------------------------------------------------------------- encoder


class EncoderParams(DeviceParams):
    """Wheel encoder settings (defaults: the lab rover's wheels; set your motor's counts)."""

    type: str = "encoder"
    wheel: Literal["left", "right"] = Field(
        "left", description="Which wheel: 'left' or 'right' as the robot faces."
    )
    track_width: float = Field(6.25, gt=0, description="Distance between the wheels, inches.")
    wheel_diameter: float = Field(2.56, gt=0, description="Wheel diameter, inches (65 mm).")
    counts_per_rev: float = Field(
        360.0, gt=0, description="Counts per wheel revolution (the motor's, after its gears)."
    )
    slip: float = Field(
        0.0,
        ge=0,
        le=1,
        description="Scale of the wheel's slip: each step it turns (1 + slip·|normal()|) times "
        "the distance its contact point moved.",
    )

    def noise_keys(self) -> list[str]:
        """``slip`` if it is on (``simmer check``'s summary)."""
        return ["slip"] if self.slip else []


class Encoder(Device):
    """Cumulative counts of one wheel; ``e0`` reads them, ``e0-1`` reads them and resets to 0.

    The wheel's contact point moves ahead by the robot's forward motion plus its turn times
    half the track width (forward for the left wheel when the robot turns clockwise in the
    window). Sideways motion (a holonomic drive's) turns no wheel. Counts are whole: the
    wheel's angle in counts, rounded down, so they go down when it turns back.
    """

    Params = EncoderParams
    default_outline: ClassVar[FloatArray] = rectangle(0.6, 1.0)

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, EncoderParams)
        self.settings = params
        # the robot frame's x points to the robot's left in the window (see RobotView.moved)
        self.offset = params.track_width / 2.0 * (1.0 if params.wheel == "left" else -1.0)
        self.counts_per_inch = params.counts_per_rev / (math.pi * params.wheel_diameter)
        self.angle = 0.0
        """The wheel's angle since the start, in counts (not rounded)."""
        self.zero = 0
        """The count a reset made 0."""
        self.slips = np.zeros(0)
        """This block's slips, each ``slip * |normal()|``, one for each step the wheel turns."""
        self.slip_at = 0

    def update(self, world: World) -> None:
        """Turn the wheel by this step's motion, with slip."""
        robot = world.robot
        arc = robot.moved.y + math.radians(robot.turned) * self.offset
        if arc == 0.0:
            return
        if self.settings.slip:
            if self.slip_at == len(self.slips):  # drawn a block at a time, as the IMU's walk
                self.slips = self.settings.slip * np.abs(self.rng.standard_normal(WALK_BLOCK))
                self.slip_at = 0
            arc *= 1.0 + float(self.slips[self.slip_at])
            self.slip_at += 1
        self.angle += arc * self.counts_per_inch

    @property
    def count(self) -> int:
        """The counts since the start or the last reset."""
        return math.floor(self.angle + COUNT_SLACK) - self.zero

    def simulate(self, value: float, world: World) -> float:
        """The count; with value 1, the count before resetting it to 0."""
        if value not in (0.0, 1.0):
            raise CommandError(
                f"{self.id} reads its count ({self.id}) or reads and resets it "
                f"({self.id}-1), not value {value:g}"
            )
        count = self.count
        if value == 1.0:
            self.zero = math.floor(self.angle + COUNT_SLACK)
        return float(count)
