"""The device interface every device kind honours, built-in or a user's own.

A device kind is a subclass of :class:`Device` with

* ``category``: ``"motor"``, ``"drive"`` or ``"sensor"`` (which configuration table it lives in);
* ``Params``: a :class:`DeviceParams` subclass (a pydantic model) listing its settings with
  defaults, so a configuration is checked before anything runs;
* ``simulate(value, world) -> float``: answer one command addressed to the device;
* optionally ``update(world)``: called once per simulation step (a gyroscope integrates here);
* optionally ``shapes(world)``: what to draw of its latest measurement.

It is registered by name with :func:`simmer.devices.register_device_kind`. The constructor takes
the device id, its validated parameters and its own random stream (from the run's seed and the
device id): every random draw must come from that generator, so a seeded run is repeatable and
one device's draws never shift another's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar, Literal, Protocol, SupportsIndex

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field
from pydantic_core import PydanticCustomError

from simmer.devices.plugins import by_plugin_file
from simmer.geometry import BoolArray, FloatArray, Pose, Vec2, rectangle

Category = Literal["motor", "drive", "sensor"]

NOISE_BLOCK = 64
"""N(0, 2) values a built-in device draws from its stream at once (:meth:`Device.gauss`)."""


def _not_bool(value: Any) -> Any:
    """Refuse true and false where a whole number belongs (pydantic reads them as 1 and 0)."""
    if isinstance(value, bool):
        raise PydanticCustomError("whole_number", "must be a whole number")
    return value


Whole = Annotated[int, BeforeValidator(_not_bool)]
"""A whole number setting (a port, a count, a seed...): ``true`` is not 1. ``36.0`` is 36, as
an original config.py computing ``border_pixels = floor_segment_length * ppi`` needs."""
Color = tuple[Whole, Whole, Whole]
"""RGB, each 0 to 255."""

SETTINGS_CONFIG = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
"""The configuration of every settings model (top-level settings, device parameters and the
models nested in them): an unknown key is an error, values never change, and no number may be
NaN or infinite (TOML's ``nan`` and ``inf``, a config.py's ``float('nan')``): one such value
makes every later reading NaN or crashes the window. A subclass of :class:`DeviceParams`
inherits it; give a model nested in one ``model_config = SETTINGS_CONFIG`` too."""


def _mount_shape(value: Any) -> Any:
    """Refuse anything but two or three values in one line, before the values themselves are
    checked (two tuple types in a union would each report their own complaint)."""
    if isinstance(value, list | tuple) and len(value) in (2, 3):
        return value
    raise PydanticCustomError("mount", "must be [x, y] (or [x, y, height]) in inches")


Mount = Annotated[tuple[float, ...], BeforeValidator(_mount_shape)]
"""A device's place on the robot: [x, y] or [x, y, height], inches."""


class DeviceParams(BaseModel):
    """Settings every device has (BEHAVIOUR §4). Kinds subclass this to add their own.

    Checks beyond single fields go in two methods returning (key, message) pairs:
    :meth:`problems` for mistakes that stop the device working (always errors), and
    :meth:`strict_problems` for settings the original SimMeR ran but a native configuration may
    not have (errors in a TOML file, warnings for an original ``config.py``).
    """

    model_config = SETTINGS_CONFIG

    def __reduce_ex__(self, protocol: SupportsIndex) -> str | tuple[Any, ...]:
        """Pickle as usual, but an instance of a plug-in's class names the plug-in's file, so
        another process loads it (:mod:`simmer.devices.plugins`)."""
        return by_plugin_file(type(self), super().__reduce_ex__(protocol))

    type: str = Field(description="Registered device kind, e.g. 'ultrasonic'.")
    position: Mount = Field(
        (0.0, 0.0), description="[x, y] (optionally [x, y, height]) in the robot frame, inches."
    )
    rotation: float = Field(0.0, description="Degrees from the robot's +y axis.")
    visible: bool = Field(True, description="Draw the device's outline.")
    outline: tuple[tuple[float, float], ...] | None = Field(
        None, min_length=3, description="Polygon in the device frame; the kind's default if unset."
    )
    color: Color = Field((0, 0, 255), description="RGB colour of the outline.")

    def problems(self) -> list[tuple[str, str]]:
        """Mistakes that involve several settings, as (key, message) pairs; none by default."""
        return []

    def strict_problems(self) -> list[tuple[str, str]]:
        """Settings the original SimMeR ran that SimMeR 2 refuses in its own format; none by
        default."""
        return []


class MazeView(Protocol):
    """The maze as a device sees it (:class:`simmer.config.maze.Maze` is one): cells of side
    ``cell`` in, ``cells`` as the configuration's walls matrix (0: solid), wall lines
    ``hwall``/``vwall``, ``segments`` (rows of x1, y1, x2, y2) and the floor's tiles of side
    ``tile`` (``floor_white[row, column]``)."""

    cells: tuple[tuple[int, ...], ...]
    cell: float
    tile: float
    hwall: BoolArray
    vwall: BoolArray

    @property
    def segments(self) -> FloatArray:
        """The walls as segments."""
        ...

    @property
    def floor_white(self) -> BoolArray:
        """Which floor tiles are white."""
        ...

    def cast_ray(self, x: float, y: float, heading: float, limit: float = math.inf) -> float:
        """Distance from (x, y) along ``heading`` to the first wall (inf if beyond ``limit``)."""
        ...


class BlockView(Protocol):
    """The block as a device sees it (:class:`simmer.config.maze.Block` is one): its centre,
    rotation and side, its outline ``segments``, and whether a gripper holds it."""

    x: float
    y: float
    rotation: float
    size: float
    segments: FloatArray
    held: Pose | None

    def cast_ray(self, x: float, y: float, heading: float) -> float:
        """Distance from (x, y) along ``heading`` to the block's outline; inf if it misses."""
        ...

    def hold(self, robot: Pose) -> None:
        """A gripper of the robot at ``robot`` has closed on the block."""
        ...

    def release(self) -> None:
        """The gripper has let it go where it is."""
        ...


class RobotView(Protocol):
    """The robot as a device sees it (:class:`simmer.world.robot.Robot` is one)."""

    pose: Pose
    start_pose: Pose
    """Where the robot started (a LiDAR's first scan is made there)."""
    turned: float
    """Degrees turned during the last step (what a gyroscope senses)."""
    moved: Vec2
    """Inches moved during the last step, in the robot's frame at the step's start (x toward
    the robot's left as the window shows it, y ahead; an IMU and an encoder sense it); 0 in a
    step the robot was blocked or placed by hand."""
    height: float
    outline: FloatArray
    devices: dict[str, Device]
    motors: dict[str, Any]
    drives: dict[str, Any]
    sensors: dict[str, Device]

    @property
    def any_drive_moving(self) -> bool:
        """True while any drive still has commanded motion left."""
        ...


class World(Protocol):
    """What a device may look at when it simulates: the simulation implements this. Devices
    see the world only through these small views, so they never import it."""

    @property
    def time(self) -> float:
        """Simulated seconds since the start."""
        ...

    @property
    def dt(self) -> float:
        """Length of one step in seconds (1 / frame_rate)."""
        ...

    @property
    def maze(self) -> MazeView:
        """The maze: walls and floor."""
        ...

    @property
    def block(self) -> BlockView:
        """The block."""
        ...

    @property
    def robot(self) -> RobotView:
        """The robot the device is mounted on."""
        ...


@dataclass(frozen=True)
class Segment:
    """A line to draw, world frame, inches."""

    start: Vec2
    end: Vec2
    color: Color


@dataclass(frozen=True)
class Circle:
    """A circle to draw, world frame, inches."""

    center: Vec2
    radius: float
    color: Color


Shape = Segment | Circle
"""What a device draws to show its latest measurement (:meth:`Device.shapes`)."""


class Device:
    """Base class of every device kind; see the module docstring for the interface."""

    category: ClassVar[Category] = "sensor"
    kind: ClassVar[str] = ""
    Params: ClassVar[type[DeviceParams]] = DeviceParams
    default_outline: ClassVar[FloatArray] = rectangle(1.0, 1.0)
    readings: ClassVar[tuple[str, ...]] = ("",)
    """What its commands read, each a column of a run's trace named by the id and this suffix:
    one reading (``""``) for most kinds; an IMU's three axes (``"", "-1", "-2"``: ``i0``,
    ``i0-1``, ``i0-2``)."""
    block_noise: ClassVar[bool] = False
    """True on a kind whose stream gives nothing but :meth:`gauss` values: it draws them
    :data:`NOISE_BLOCK` at a time. Only the class that says so itself (not a subclass, which
    may draw from ``rng`` directly and so would see its stream's order change)."""

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        self.id = device_id
        self.params = params
        self.rng = rng
        self._blocked = type(self).__dict__.get("block_noise", False) is True
        self._gauss_block: list[float] = []
        self._gauss_next = 0
        self.position = Vec2(params.position[0], params.position[1])
        self.rotation = float(params.rotation)
        self.visible = params.visible
        self.outline: FloatArray = (
            np.asarray(params.outline, dtype=np.float64)
            if params.outline is not None
            else self.default_outline.copy()
        )

    def __reduce_ex__(self, protocol: SupportsIndex) -> str | tuple[Any, ...]:
        """Pickle as usual, but an instance of a plug-in's class names the plug-in's file, so
        another process loads it (:mod:`simmer.devices.plugins`)."""
        return by_plugin_file(type(self), super().__reduce_ex__(protocol))

    # -- the interface -------------------------------------------------------------------

    def simulate(self, value: float, world: World) -> float:
        """Answer one command addressed to this device; override in every kind."""
        raise NotImplementedError

    def update(self, world: World) -> None:
        """Advance per-step state (called once per step); most devices need nothing here."""

    def shapes(self, world: World) -> list[Shape]:
        """Shapes showing the latest measurement, for the renderer; none by default."""
        return []

    # -- helpers for kinds ---------------------------------------------------------------

    @property
    def mount_height(self) -> float | None:
        """Height from the optional third position value, if given."""
        return self.params.position[2] if len(self.params.position) == 3 else None

    def world_pose(self, robot_pose: Pose) -> Pose:
        """Where the device is, and which way it faces, in the world."""
        x, y, heading = robot_pose
        px, py = self.position
        rad = math.radians(heading)
        c, s = math.cos(rad), math.sin(rad)
        return Pose(x + px * c - py * s, y + px * s + py * c, heading + self.rotation)

    def percent_error(self, value: float, error: float) -> float:
        """SimMeR's percent error: ``value + gauss(0, 2) · error · value`` (BEHAVIOUR §4)."""
        if error == 0.0 or value == 0.0:  # nothing to scale: no draw (a w0-0 poll draws none)
            return value
        return value + self.gauss() * error * value

    def gauss(self) -> float:
        """The stream's next N(0, 2) value: what ``rng.normal(0, 2)`` gives, in the same order.

        A kind with :attr:`block_noise` takes it from a block of :data:`NOISE_BLOCK` drawn at
        once (NumPy's vector draw gives the scalar draws' values: a recorded run replays bit
        for bit), which costs a list index instead of a NumPy call per sample."""
        if not self._blocked:
            return float(self.rng.normal(0.0, 2.0))
        k = self._gauss_next
        if k == len(self._gauss_block):
            self._gauss_block = self.rng.normal(0.0, 2.0, NOISE_BLOCK).tolist()
            k = 0
        self._gauss_next = k + 1
        return self._gauss_block[k]
