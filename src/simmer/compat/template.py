"""Run a device class written for the original SimMeR (from its ``devices/template.py``).

Such a class is built from an info dictionary, answers ``simulate(value, environment)`` with a
number, may have ``update(environment)``, and sets ``d_type``. The adapter kind
``simmer_device`` (a sensor) names the file and class::

    [sensors.t0]
    type = "simmer_device"
    module = "devices/template.py"   # relative to the configuration file
    class_name = "Template"
    position = [0, 3]
    threshold = 2                     # any other key goes into the info dictionary

The class is built on first use, from an info dictionary holding ``id``, ``position``,
``rotation``, ``visible`` and every other key given (``outline`` as ``pygame.math.Vector2``s).
``environment`` is a dictionary like SimMeR's: ``environment['ROBOT']`` (``position``,
``rotation``, ``pose``, ``outline``, ``height``, and ``sensors``, ``drives`` and ``motors``:
views of every device by id, whose ``simulate(value, environment)`` asks the real device),
``environment['MAZE']`` (``walls``, ``wall_segment_length``, ``floor_segment_length``,
``reduced_walls``), ``environment['BLOCK']`` (``position``, ``rotation``, ``size``,
``height``, ``block_square``) and ``environment['TIME']`` (simulated seconds). Before each call
the device's ``position_global`` and ``rotation_global`` are set, ``import config as CONFIG``
gives the running configuration's settings (and ``maze_dim_x``, ``maze_dim_y``), and
``import utilities`` the original's helpers (:mod:`simmer.compat.utilities`). Drawing methods
(``draw``, ``draw_measurement``) are not called.

The registry imports this module when a configuration first names the kind. A simulation holding
such a device pickles (for a process pool's workers): the user's object goes as its attributes,
and the other process imports the file again and restores the object without calling
``__init__``.
"""

from __future__ import annotations

import importlib.util
import inspect
import sys
import types
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from pydantic import ConfigDict, Field, ValidationInfo, field_validator

from simmer.compat import utilities
from simmer.compat.standins import StandIns, Vector2
from simmer.devices import Device, DeviceParams, Drive, Motor, World
from simmer.devices.base import Category
from simmer.errors import CommandError, describe_exception

KIND = "simmer_device"


@dataclass(frozen=True)
class LoadedModule:
    """A user's device module, imported once with the stand-ins, and its ``config`` module."""

    module: types.ModuleType
    config: types.ModuleType


_LOADED: dict[tuple[str, int], LoadedModule] = {}


def remember_module(module: types.ModuleType, config: types.ModuleType) -> None:
    """Keep a device module imported while a ``config.py`` ran, so it is not imported again."""
    path = Path(str(module.__file__)).resolve()
    _LOADED[(str(path), path.stat().st_mtime_ns)] = LoadedModule(module, config)


def module_file(cls: type) -> Path | None:
    """The file of the remembered device module that defines ``cls``, if any."""
    for loaded in _LOADED.values():
        if vars(loaded.module).get(cls.__name__) is cls:
            return Path(str(loaded.module.__file__)).resolve()
    return None


def load_module(path: Path) -> LoadedModule:
    """Import a user's device file with the stand-ins in place (once per file version)."""
    path = path.resolve()
    key = (str(path), path.stat().st_mtime_ns)
    if key not in _LOADED:
        config = types.ModuleType("config", "The running configuration's settings.")
        name = f"devices.{path.stem}"
        with StandIns(path.parent.parent, [path.parent], config):
            spec = importlib.util.spec_from_file_location(name, path)
            assert spec is not None
            assert spec.loader is not None
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
        _LOADED[key] = LoadedModule(module, config)
    return _LOADED[key]


def check_device_class(cls: object, where: str) -> type:
    """Raise ValueError, saying what to change, unless ``cls`` looks like a SimMeR device class."""
    if not inspect.isclass(cls):
        raise ValueError(f"{where} is not a class")
    simulate = getattr(cls, "simulate", None)
    if not callable(simulate):
        raise ValueError(
            f"{where} has no simulate method; add `def simulate(self, value, environment):` "
            "returning a number"
        )
    for method, wanted in (("simulate", "value, environment"), ("update", "environment")):
        function = getattr(cls, method, None)
        if function is None:
            continue
        try:
            inspect.signature(function).bind(None, *wanted.split(", "))
        except TypeError:
            raise ValueError(
                f"{where}.{method} must be defined as `def {method}(self, {wanted}):`"
            ) from None
    return cls


class SimmerDeviceParams(DeviceParams):
    """A SimMeR-style device class: its file and name, plus its info dictionary's keys."""

    model_config = ConfigDict(extra="allow", frozen=True)

    type: str = KIND
    module: str = Field("", description="The class's .py file, relative to the configuration.")
    class_name: str = Field("", description="The class's name, e.g. 'Template'.")

    @field_validator("module")
    @classmethod
    def _resolve(cls, value: str, info: ValidationInfo) -> str:
        if not value:
            return value
        base = Path((info.context or {}).get("base_dir", "."))
        path = (base / value).resolve()
        if not path.is_file():
            raise ValueError(
                f"no file {value!r} next to the configuration ({base}); give the device file's "
                "path relative to the configuration file, e.g. 'devices/template.py'"
            )
        return str(path)

    @field_validator("class_name")
    @classmethod
    def _find_class(cls, value: str, info: ValidationInfo) -> str:
        module_path = info.data.get("module")
        if not (module_path and value):
            return value
        path = Path(module_path)
        try:
            module = load_module(path).module
        except (Exception, SystemExit) as exc:  # sys.exit() in the file must not end `check`
            raise ValueError(f"importing {path.name} failed: {describe_exception(exc)}") from None
        if not hasattr(module, value):
            classes = [n for n, o in vars(module).items() if inspect.isclass(o)]
            raise ValueError(f"{path.name} has no class {value!r}; it has: {', '.join(classes)}")
        check_device_class(getattr(module, value), f"class {value} in {path.name}")
        return value

    def problems(self) -> list[tuple[str, str]]:
        """The file and class must be named (checked here so the defaults stay buildable)."""
        found = []
        if not self.module:
            found.append(("module", "missing: the device's file, e.g. 'devices/template.py'"))
        if not self.class_name:
            found.append(("class_name", "missing: the device class's name, e.g. 'Template'"))
        return found


class _DeviceView:
    """One device as ``environment['ROBOT'].sensors[id]`` (or ``drives``, ``motors``) shows it.

    ``simulate(value, environment)`` asks the real SimMeR 2 device, so a sensor measures, a
    drive starts moving (+inf, or NaN while a drive is busy) and a motor gives its odometer.
    """

    def __init__(self, device: Device, world: World) -> None:
        self._device = device
        self._world = world
        self.id = device.id
        self.d_type = device.category
        self.position = Vector2(device.position.x, device.position.y)
        self.rotation = device.rotation

    @property
    def position_global(self) -> Vector2:
        """Where the device is in the world now."""
        pose = self._device.world_pose(self._world.robot.pose)
        return Vector2(pose.x, pose.y)

    @property
    def rotation_global(self) -> float:
        """Which way the device faces in the world now, degrees."""
        return float(self._device.world_pose(self._world.robot.pose).heading)

    def simulate(self, value: float, environment: Any = None) -> float:
        """The device's answer to ``value`` (it sees the same world as ``environment``)."""
        return float(self._device.simulate(value, self._world))


class _DriveView(_DeviceView):
    """A drive: also ``move_buffer``, the motion still to do (non-zero while moving)."""

    def __init__(self, drive: Drive, world: World) -> None:
        super().__init__(drive, world)
        self._drive = drive

    @property
    def move_buffer(self) -> float:
        """Inches (or degrees) of commanded motion left."""
        return self._drive.remaining


class _MotorView(_DeviceView):
    """A motor: also ``odometer``, the wheel's travel so far."""

    def __init__(self, motor: Motor, world: World) -> None:
        super().__init__(motor, world)
        self._motor = motor

    @property
    def odometer(self) -> float:
        """Inches the wheel has turned through."""
        return self._motor.odometer


class _RobotView:
    """``environment['ROBOT']``: the robot's live pose, outline, height and devices."""

    def __init__(self, world: World) -> None:
        self._world = world
        robot = world.robot
        self.outline = [Vector2(x, y) for x, y in robot.outline]
        self.height = robot.height
        self.sensors = {i: _DeviceView(d, world) for i, d in robot.sensors.items()}
        self.drives = {i: _DriveView(d, world) for i, d in robot.drives.items()}
        self.motors = {i: _MotorView(d, world) for i, d in robot.motors.items()}

    @property
    def pose(self) -> Any:
        """The pose (x, y, heading)."""
        return self._world.robot.pose

    @property
    def position(self) -> Vector2:
        """Centre of the robot, inches."""
        return Vector2(self.pose.x, self.pose.y)

    @property
    def rotation(self) -> float:
        """Heading, degrees."""
        return float(self.pose.heading)


def _segments(array: np.ndarray[Any, Any]) -> list[list[Vector2]]:
    return [[Vector2(a, b), Vector2(c, d)] for a, b, c, d in array.tolist()]


class _MazeView:
    """``environment['MAZE']``: the wall matrix, sizes and wall segments."""

    def __init__(self, world: World) -> None:
        maze = world.maze
        self.walls = [list(row) for row in maze.cells]
        self.wall_segment_length = maze.cell
        self.floor_segment_length = maze.tile
        self.reduced_walls = _segments(maze.segments)


class _BlockView:
    """``environment['BLOCK']``: the block's live position, size and edges."""

    def __init__(self, world: World) -> None:
        self._world = world

    @property
    def position(self) -> Vector2:
        """Centre of the block."""
        return Vector2(self._world.block.x, self._world.block.y)

    @property
    def rotation(self) -> float:
        """Rotation, degrees."""
        return self._world.block.rotation

    @property
    def size(self) -> float:
        """Side length (also its height)."""
        return self._world.block.size

    height = size

    @property
    def block_square(self) -> list[list[Vector2]]:
        """The four edges as [start, end] pairs."""
        return _segments(self._world.block.segments)


class Environment(dict[str, Any]):
    """What SimMeR passed as ``environment``: keys ROBOT, MAZE, BLOCK and TIME."""

    def __init__(self, world: World) -> None:
        super().__init__(
            ROBOT=_RobotView(world), MAZE=_MazeView(world), BLOCK=_BlockView(world), TIME=0.0
        )


def config_values(world: World) -> dict[str, Any]:
    """Settings a SimMeR device may read as ``CONFIG.<name>``."""
    config = getattr(world, "config", None)
    if config is None:
        return {}
    values: dict[str, Any] = config.settings.model_dump()
    values["maze_dim_x"] = len(values["walls"][0]) * values["wall_segment_length"]
    values["maze_dim_y"] = len(values["walls"]) * values["wall_segment_length"]
    return values


def _plain(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


class SimmerDevice(Device):
    """A device class written for the original SimMeR; any other key goes into its info dict.

    See docs/migrating.md. The class is imported from ``module`` and built from its info
    dictionary on first use; it answers commands as a sensor.
    """

    Params = SimmerDeviceParams
    category: ClassVar[Category] = "sensor"

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, SimmerDeviceParams)
        self.settings = params
        skip = {"type", "module", "class_name", "position", "rotation", "visible", "outline"}
        self.info: dict[str, Any] = {
            "id": device_id,
            "position": list(params.position),
            "rotation": params.rotation,
            "visible": params.visible,
        }
        if "outline" in params.model_fields_set and params.outline is not None:
            self.info["outline"] = [Vector2(x, y) for x, y in params.outline]
        self.info |= {
            k: _plain(v) for k, v in params.model_dump(exclude_unset=True).items() if k not in skip
        }
        self.loaded: LoadedModule | None = None
        self.instance: Any = None
        self.unpickled: dict[str, Any] | None = None
        """The user's object's attributes, from a pickle, until the object is built again."""
        self.environment: Environment | None = None

    def __getstate__(self) -> dict[str, Any]:
        """Pickle without the user's module, which no other process can import by its name
        (``devices.<name>`` exists only while it loads), nor the views of the world: they are
        made again on first use. The user's object is carried as its attributes."""
        state = self.__dict__.copy()
        if self.instance is not None:
            state["unpickled"] = vars(self.instance)
        state.update(loaded=None, instance=None, environment=None)
        return state

    def _prepare(self, world: World) -> tuple[Any, Environment]:
        """Build the user's object on first use; refresh its global pose and the time."""
        if self.loaded is None:
            self.loaded = load_module(Path(self.settings.module))
            self.loaded.config.__dict__.update(config_values(world))
        if self.instance is None:
            user_class = getattr(self.loaded.module, self.settings.class_name)
            if self.unpickled is None:
                self.instance = user_class(dict(self.info))
            else:  # from a pickle: the same object, without running __init__ again
                self.instance = user_class.__new__(user_class)
                vars(self.instance).update(self.unpickled)
                self.unpickled = None
        if self.environment is None:
            self.environment = Environment(world)
        pose = self.world_pose(world.robot.pose)
        self.instance.position_global = Vector2(pose.x, pose.y)
        self.instance.rotation_global = pose.heading
        self.environment["TIME"] = world.time
        utilities.CONTEXT.rng = self.rng
        utilities.CONTEXT.config = self.loaded.config
        return self.instance, self.environment

    def simulate(self, value: float, world: World) -> float:
        """Call the class's ``simulate(value, environment)``; its answer must be a number."""
        instance, environment = self._prepare(world)
        answer = instance.simulate(value, environment)
        try:
            return float(answer)
        except (TypeError, ValueError):
            raise CommandError(
                f"{self.settings.class_name}.simulate returned {answer!r}, not a number; make it "
                "return a float"
            ) from None

    def update(self, world: World) -> None:
        """Call the class's ``update(environment)`` each step, if it has one.

        An exception switches the device off (the simulation logs it once and carries on).
        """
        instance, environment = self._prepare(world)
        if hasattr(instance, "update"):
            instance.update(environment)


__all__ = ["KIND", "Environment", "SimmerDevice", "SimmerDeviceParams"]
