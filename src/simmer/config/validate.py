"""Validate configuration data: every problem at once, in a student's words.

Every problem is collected (not just the first) and reported as ``file: key.path: message``,
with a "did you mean" for near misses, so a student can fix a file in one pass.

An original SimMeR ``config.py`` is checked less strictly (``original=True``): what the original
ran although the native format refuses it (BEHAVIOUR §6.3: a hidden block, ``beamwidth = 0``, an
omni-wheel or arc drive, a motor among the sensors) becomes a warning in
:attr:`SimConfig.warnings`, written like an error. What would crash or mean nothing (a robot
starting in a wall, a drive that never moves) stays an error.

Both readers use it: :mod:`simmer.config.loader` (TOML) and :mod:`simmer.config.simmer_py` (an
original ``config.py``, read into the same data), so neither imports the other's module.
"""

from __future__ import annotations

import difflib
import math
import reprlib
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, get_args

import numpy as np
from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from simmer.config.models import (
    DEVICE_GROUPS,
    MAX_CELLS_PER_SIDE,
    MAX_DRAWING_PIXELS,
    MAX_FLOOR_TILES,
    DeviceSpec,
    Group,
    Settings,
    SimConfig,
)
from simmer.devices import DeviceKinds
from simmer.devices.plugins import plugin_kinds
from simmer.errors import ConfigError, ConfigIssue, DeviceKindError, ScenarioError
from simmer.geometry import (
    FloatArray,
    Pose,
    place_polygon,
    polygon_hits_grid,
    polygons_overlap,
)

if TYPE_CHECKING:
    from simmer.config.maze import Maze

DEFAULT_KIND = {"motors": "motor", "drives": "drive"}
CATEGORY_OF_GROUP = {"motors": "motor", "drives": "drive", "sensors": "sensor"}
GROUP_OF_CATEGORY: dict[str, Group] = {"motor": "motors", "drive": "drives", "sensor": "sensors"}
ORIGINAL_RUNS = "; the original SimMeR ran this, so SimMeR 2 does too (a TOML file may not)"
"""Ends a warning about what an original config.py may do but a native file may not."""


def config_from_dict(
    data: dict[str, Any], source: str, base_dir: Path, *, original: bool = False
) -> SimConfig:
    """Validate configuration data; raise :class:`ConfigError` listing every issue found.

    ``original``: the data comes from an original SimMeR ``config.py``, so what the original
    ran is allowed, with a warning (see the module docstring).
    """
    data = dict(data)
    found = _Found(original)
    issues = found.errors
    groups: dict[str, Any] = {group: data.pop(group, {}) for group in DEVICE_GROUPS}
    found.kinds = _load_plugins(data.get("plugins", []), base_dir, issues)
    issues += resolve_maze(data, base_dir)
    oversize = oversize_walls(data.get("walls"))
    if oversize is not None:
        issues.append(oversize)
        del data["walls"]  # validate the rest without copying the matrix

    settings: Settings | None = None
    try:
        settings = Settings.model_validate(data)
    except ValidationError as exc:
        issues += _issues_from_validation(exc, "", Settings)

    declared = {
        group: [str(device_id) for device_id in table] if isinstance(table, dict) else []
        for group, table in groups.items()
    }
    devices = _validate_devices(groups, declared, found, base_dir)
    issues += _check_drive_motors(devices, groups["drives"], declared["motors"])
    if settings is not None:
        maze_issues = [] if oversize else _check_walls(settings) or _check_sizes(settings)
        issues += maze_issues + _check_references(settings, declared)
        if not (oversize or maze_issues):  # the placement check builds the maze
            _check_placement(settings, found)
            issues += check_project(settings)
    if issues:
        raise ConfigError(source, issues)
    assert settings is not None
    return SimConfig(settings, tuple(devices), source, tuple(found.warnings), kinds=found.kinds)


@dataclass
class _Found:
    """The issues found so far: errors, and warnings for an original ``config.py``."""

    original: bool
    errors: list[ConfigIssue] = field(default_factory=list)
    warnings: list[ConfigIssue] = field(default_factory=list)
    kinds: DeviceKinds = field(default_factory=DeviceKinds)
    """The kinds the configuration may use (its plug-ins' as well, once loaded)."""

    def strict(self, key: str, message: str, warning: str | None = None) -> None:
        """Something only the native format refuses: an error, or for an original config.py a
        warning (saying ``warning``, if given, instead of ``message``)."""
        if self.original:
            self.warnings.append(ConfigIssue(key, (warning or message) + ORIGINAL_RUNS))
        else:
            self.errors.append(ConfigIssue(key, message))


# ----------------------------------------------------------------------------- maze


def resolve_maze(data: dict[str, Any], base_dir: Path) -> list[ConfigIssue]:
    """Set the settings a configuration's ``maze`` supplies (a file, a course maze's name or
    a ``[maze]`` table to generate; docs/mazes.md) in ``data``, where it does not set them
    itself; the problems, under the key ``maze``. Data holding ``walls`` already (a recording's,
    or a configuration validated once) keeps them: the maze was resolved when it was made."""
    raw = data.get("maze")
    if raw is None or "walls" in data:
        return []
    issues = _maze_settings(raw, data, base_dir)
    if issues:
        del data["maze"]  # said once, here
    return issues


def _maze_settings(raw: Any, data: dict[str, Any], base_dir: Path) -> list[ConfigIssue]:
    """:func:`resolve_maze` for a ``maze`` that is set."""
    from simmer.config.mazegen import generate
    from simmer.config.mazes import COURSE_MAZES, course_maze, read_maze
    from simmer.config.project import GenerateSettings
    from simmer.errors import GenerateError

    try:
        if isinstance(raw, str):
            maze = course_maze(raw) if raw in COURSE_MAZES else read_maze(base_dir / raw)
        elif isinstance(raw, dict):
            maze = generate(GenerateSettings.model_validate(raw)).maze
        else:
            names = ", ".join(COURSE_MAZES)
            message = f"is {raw!r}; give a maze file, a course maze's name ({names}) or a table"
            return [ConfigIssue("maze", message)]
    except ConfigError as exc:
        return [ConfigIssue("maze", f"{issue.render(exc.source)}") for issue in exc.issues]
    except ValidationError as exc:
        return _issues_from_validation(exc, "maze", GenerateSettings)
    except GenerateError as exc:
        return [ConfigIssue("maze", str(exc))]
    for key, value in maze.settings_data().items():
        if key == "zones":
            zones = data.setdefault("zones", {})
            if isinstance(zones, dict):
                for name, cells in value.items():
                    if zones.get(name) is None:
                        zones[name] = cells
        else:
            data.setdefault(key, value)
    return []


# ----------------------------------------------------------------------------- plugins


def _load_plugins(plugins: Any, base_dir: Path, issues: list[ConfigIssue]) -> DeviceKinds:
    """Load each plug-in (a .py file relative to the configuration, or an installed module's
    name) for this configuration alone, adding what goes wrong to ``issues``; the kinds the
    configuration may use."""
    if not isinstance(plugins, list | tuple):
        return DeviceKinds()  # the Settings model reports the wrong type
    loaded: list[str] = []
    registered_by: dict[str, tuple[str, str]] = {}  # a plug-in kind -> (plug-in, its entry)
    for i, entry in enumerate(plugins):
        if not isinstance(entry, str):
            continue
        key = f"plugins[{i}]"
        try:
            name = _plugin_name(entry, base_dir)
            kinds = plugin_kinds(name)
        except FileNotFoundError:
            issues.append(
                ConfigIssue(
                    key,
                    f"no file {entry!r} next to the configuration ({base_dir}); "
                    "give a path relative to the configuration file",
                )
            )
            continue
        except (Exception, SystemExit) as exc:  # sys.exit() in a plug-in must not end `check`
            issues.append(ConfigIssue(key, _describe_plugin_error(entry, exc)))
            continue
        loaded.append(name)
        for kind in kinds:
            first, first_entry = registered_by.setdefault(kind, (name, entry))
            if first != name:
                message = f"{entry} registers device kind {kind!r}, as {first_entry} does"
                issues.append(ConfigIssue(key, message + "; rename one of the two"))
    return DeviceKinds(tuple(dict.fromkeys(loaded)))


def _plugin_name(entry: str, base_dir: Path) -> str:
    """How :func:`plugin_kinds` knows a plug-in: a file (relative to the configuration) by its
    absolute path, an installed module by its name."""
    if entry.endswith(".py") or "/" in entry or "\\" in entry:
        path = (base_dir / entry).resolve()
        if not path.is_file():
            raise FileNotFoundError(path)
        return str(path)
    return entry


def _describe_plugin_error(entry: str, exc: Exception | SystemExit) -> str:
    if isinstance(exc, DeviceKindError):
        return f"{entry}: {exc}"
    frames = traceback.extract_tb(exc.__traceback__)
    where = ""
    for frame in reversed(frames):
        if Path(frame.filename).name == Path(entry).name:
            where = f" at line {frame.lineno}"
            break
    what = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
    if isinstance(exc, SystemExit):
        what += (
            "; a plug-in may not end the program: remove its sys.exit(), exit() or os._exit() call"
        )
    return f"importing {entry} failed{where}: {what}"


# ----------------------------------------------------------------------------- devices


def _validate_devices(
    groups: dict[str, Any], declared: dict[str, list[str]], found: _Found, base_dir: Path
) -> list[DeviceSpec]:
    """Validate every device; ``declared`` (ids by table) follows any device an original
    config.py listed in the wrong table."""
    issues = found.errors
    devices: list[DeviceSpec] = []
    seen: dict[str, str] = {}
    for group in DEVICE_GROUPS:
        table = groups[group]
        if not isinstance(table, dict):
            message = f"must be a table of devices like [{group}.xx], not {_shown(table)}"
            issues.append(ConfigIssue(group, message))
            continue
        for device_id, raw in table.items():
            key = f"{group}.{device_id}"
            if not isinstance(raw, dict):
                issues.append(ConfigIssue(key, f"must be a table of settings, not {_shown(raw)}"))
                continue
            home = _rehome(group, device_id, raw, declared, found) if found.original else group
            if home is None:
                continue
            id_problem = _id_problem(device_id)
            if id_problem:
                found.strict(
                    key,
                    id_problem,
                    f"device id {device_id!r} is not two ASCII characters, so no command can "
                    "reach it: a command names a device by its first two characters, and the "
                    "original answered 'Not Found' (v1.2) or NaN; rename it (like 'u1') to use it",
                )
            if device_id in seen:
                issues.append(
                    ConfigIssue(
                        key,
                        f"device id {device_id!r} is already used by "
                        f"[{seen[device_id]}.{device_id}]; every device needs its own id",
                    )
                )
            seen.setdefault(device_id, group)
            spec = _validate_device(key, home, device_id, raw, found, base_dir)
            if spec is not None:
                devices.append(spec)
    return devices


def _rehome(
    group: Group,
    device_id: str,
    raw: dict[str, Any],
    declared: dict[str, list[str]],
    found: _Found,
) -> Group | None:
    """The table an original config.py's device belongs in: its own ``group``, or, for a
    built-in device listed in the wrong dictionary (a motor among the sensors; the original
    answered it by id all the same), its kind's table, or None if that table has the id too."""
    name = raw.get("type", DEFAULT_KIND.get(group))
    kind = found.kinds.get(name) if isinstance(name, str) else None
    if kind is None or kind.category == CATEGORY_OF_GROUP[group]:
        return group
    home = GROUP_OF_CATEGORY[kind.category]
    key = f"{group}.{device_id}"
    declared[group].remove(device_id)
    if device_id in declared[home]:
        found.warnings.append(
            ConfigIssue(
                key,
                f"{name!r} {device_id!r} is listed among the {home} and again among the "
                f"{group}; SimMeR 2 uses the one in {home} and ignores this entry" + ORIGINAL_RUNS,
            )
        )
        return None
    declared[home].append(device_id)
    found.warnings.append(
        ConfigIssue(
            key,
            f"is a {name!r}, which belongs among the {home}, not the {group}; SimMeR 2 moves "
            f"it there (it still answers commands as {device_id!r})" + ORIGINAL_RUNS,
        )
    )
    return home


def _id_problem(device_id: str) -> str | None:
    if len(device_id) != 2 or not device_id.isascii() or not device_id.isprintable():
        return (
            f"device id {device_id!r} must be exactly two ASCII characters "
            "(like 'u0'), because commands are addressed by their first two characters"
        )
    if device_id == "xx":
        return "'xx' is reserved for the emergency stop; choose another id"
    if "," in device_id or "-" in device_id or " " in device_id:
        return f"device id {device_id!r} may not contain ',', '-' or spaces"
    return None


def _validate_device(
    key: str, group: Group, device_id: str, raw: dict[str, Any], found: _Found, base_dir: Path
) -> DeviceSpec | None:
    """Validate one device written at ``key`` that lives in ``group``."""
    issues = found.errors
    raw = dict(raw)
    if "id" in raw:
        issues.append(
            ConfigIssue(
                f"{key}.id",
                f"a device's id is the name of its table ([{key}]); delete the 'id' line",
            )
        )
        raw.pop("id")
    kind_name = raw.setdefault("type", DEFAULT_KIND.get(group))
    if kind_name is None:
        issues.append(
            ConfigIssue(
                f"{key}.type",
                "missing: say what the sensor is, one of " + _kind_list(found.kinds, "sensor"),
            )
        )
        return None
    named = isinstance(kind_name, str)
    kind = found.kinds.get(kind_name) if named else None
    if kind is None:
        hint = _did_you_mean(kind_name, list(found.kinds.all())) if named else ""
        issues.append(
            ConfigIssue(
                f"{key}.type",
                f"unknown device kind {_shown(kind_name)}{hint}; known kinds: "
                + _kind_list(found.kinds, CATEGORY_OF_GROUP[group]),
            )
        )
        return None
    if kind.category != CATEGORY_OF_GROUP[group]:
        issues.append(
            ConfigIssue(
                f"{key}.type",
                f"{kind_name!r} is a {kind.category}, so it belongs in "
                f"[{kind.category}s.{device_id}], not [{group}.{device_id}]",
            )
        )
        return None
    try:
        # base_dir lets a kind resolve file paths relative to the configuration file
        params = kind.Params.model_validate(raw, context={"base_dir": base_dir})
    except ValidationError as exc:
        issues += _issues_from_validation(exc, key, kind.Params)
        errors = exc.errors()
        unknown = {
            e["loc"][0] for e in errors if e["type"] == "extra_forbidden" and len(e["loc"]) == 1
        }
        if len(unknown) < len(errors):
            return None
        try:  # only unknown keys: the rest may hold mistakes they must not hide
            known = {name: value for name, value in raw.items() if name not in unknown}
            params = kind.Params.model_validate(known, context={"base_dir": base_dir})
        except ValidationError:
            return None
        issues += [ConfigIssue(f"{key}.{sub}", message) for sub, message in params.problems()]
        return None
    problems = params.problems()
    issues += [ConfigIssue(f"{key}.{sub}", message) for sub, message in problems]
    if problems:
        return None
    for sub, message in params.strict_problems():
        found.strict(f"{key}.{sub}", message)
    return DeviceSpec(device_id, group, str(kind_name), params)


def _kind_list(kinds: DeviceKinds, category: str) -> str:
    names = sorted(name for name, cls in kinds.all().items() if cls.category == category)
    return ", ".join(names)


# ----------------------------------------------------------------------------- cross checks


def maze_issues(settings: Settings) -> list[ConfigIssue]:
    """What is wrong with the maze of settings validated already (its shape, its sizes), for
    a tool that draws a recorded maze without its devices (``simmer plot``)."""
    return _check_walls(settings) or _check_sizes(settings)


def _check_walls(settings: Settings) -> list[ConfigIssue]:
    walls = settings.walls
    if not walls or not walls[0]:
        return [
            ConfigIssue(
                "walls", "is empty: give at least one row of cells, e.g. walls = [[1, 1], [1, 1]]"
            )
        ]
    issues = []
    width = len(walls[0])
    for r, row in enumerate(walls):
        if len(row) != width:
            issues.append(
                ConfigIssue(
                    f"walls[{r}]",
                    f"has {len(row)} cells but row 0 has {width}; every row needs the same number",
                )
            )
    if not any(cell != 0 for row in walls for cell in row):
        issues.append(ConfigIssue("walls", "has no open cell (0 means solid); use 1 for floor"))
    return issues


def oversize_walls(walls: Any) -> ConfigIssue | None:
    """A ``walls`` matrix over the size limit, found on the raw data before validation copies
    it (a 10,000 x 10,000 matrix took minutes and gigabytes to refuse)."""
    if not isinstance(walls, list | tuple):
        return None  # the Settings model reports the wrong type
    why = (
        f"at most {MAX_CELLS_PER_SIDE} rows of {MAX_CELLS_PER_SIDE} cells (the lab maze has 4 "
        "rows of 8), because every wall is stored and drawn, and a reading walks the maze cell "
        "by cell"
    )
    if len(walls) > MAX_CELLS_PER_SIDE:
        return ConfigIssue("walls", f"has {len(walls):,} rows; {why}")
    for r, row in enumerate(walls):
        if isinstance(row, list | tuple) and len(row) > MAX_CELLS_PER_SIDE:
            return ConfigIssue(f"walls[{r}]", f"has {len(row):,} cells; {why}")
    return None


def _check_sizes(settings: Settings) -> list[ConfigIssue]:
    """Refuse a floor or a drawing too large to hold, before the maze is built: floor tiles of
    1e-6 in asked for 32 PiB, a ``ppi`` of 1e300 for a window no screen can show."""
    from simmer.config.maze import floor_tiles

    s = settings
    rows, cols = len(s.walls), len(s.walls[0])
    width, height = cols * s.wall_segment_length, rows * s.wall_segment_length
    maze = f"the {_number(width)} x {_number(height)} in maze ({cols} x {rows} cells)"
    if not math.isfinite(width * height):
        return [
            ConfigIssue(
                "wall_segment_length",
                f"makes {maze} too large to compute with; the lab maze's cells are 12 in",
            )
        ]
    issues = []
    across, down = floor_tiles(cols, rows, s.wall_segment_length, s.floor_segment_length)
    if not across * down <= MAX_FLOOR_TILES:
        smallest = math.sqrt(width * height / MAX_FLOOR_TILES)
        issues.append(
            ConfigIssue(
                "floor_segment_length",
                f"{maze} makes {_number(across * down)} floor tiles of "
                f"{_number(s.floor_segment_length)} in; at most {MAX_FLOOR_TILES:,} (the lab "
                "maze has 512), because the floor pattern is held as one array: make "
                f"floor_segment_length at least about {_rounded(smallest, up=True)} in, or "
                "the maze smaller (wall_segment_length, walls)",
            )
        )
    border = 2 * s.border_pixels
    side = max(width, height) * s.ppi + border
    if not side <= MAX_DRAWING_PIXELS:
        limit = f"at most {MAX_DRAWING_PIXELS:,} pixels a side (the most graphics cards draw)"
        if border >= MAX_DRAWING_PIXELS:
            issues.append(
                ConfigIssue(
                    "border_pixels",
                    f"leaves no room for the maze in a window of {limit}; the lab uses 20",
                )
            )
        else:
            fits = (MAX_DRAWING_PIXELS - border) / max(width, height)
            issues.append(
                ConfigIssue(
                    "ppi",
                    f"draws {maze} {_number(width * s.ppi + border)} x "
                    f"{_number(height * s.ppi + border)} pixels (with the border); {limit}: "
                    f"make ppi at most {_rounded(fits, up=False)}, or the maze smaller",
                )
            )
    return issues


def _check_drive_motors(
    devices: list[DeviceSpec], drives: Any, motor_ids: list[str]
) -> list[ConfigIssue]:
    """Every motor a drive names must be declared (a declared but invalid one is reported
    where it is declared, not again here). A drive with other mistakes is checked from its
    table as written, so that one mistake does not hide another."""
    named = {
        spec.id: list(getattr(spec.params, "motors", ()))
        for spec in devices
        if spec.group == "drives"
    }
    valid = {spec.id for spec in devices}
    for device_id, raw in (drives if isinstance(drives, dict) else {}).items():
        if device_id not in valid and isinstance(raw, dict) and isinstance(raw.get("motors"), list):
            named[device_id] = raw["motors"]
    issues = []
    for drive_id, motors in named.items():
        for i, motor in enumerate(motors):
            if isinstance(motor, str) and motor not in motor_ids:
                hint = _did_you_mean(motor, motor_ids)
                known = ", ".join(motor_ids) or "none"
                issues.append(
                    ConfigIssue(
                        f"drives.{drive_id}.motors[{i}]",
                        f"no motor {motor!r}{hint}; the motors are: {known}",
                    )
                )
    return issues


def _check_references(settings: Settings, declared: dict[str, list[str]]) -> list[ConfigIssue]:
    issues = []
    group_of = {device_id: group for group, ids in declared.items() for device_id in ids}
    sensor_ids = declared["sensors"]
    for i, device_id in enumerate(settings.simulate_list):
        if device_id not in sensor_ids:
            what = (
                f"{device_id!r} is a {group_of[device_id][:-1]}"
                if device_id in group_of
                else (f"no sensor {device_id!r}{_did_you_mean(device_id, sensor_ids)}")
            )
            issues.append(
                ConfigIssue(
                    f"simulate_list[{i}]",
                    f"{what}; list only sensor ids ({', '.join(sensor_ids) or 'none'})",
                )
            )
    if settings.port_rx == settings.port_tx:
        issues.append(ConfigIssue("port_tx", f"must differ from port_rx ({settings.port_rx})"))
    return issues


def _check_placement(settings: Settings, found: _Found) -> None:
    """The robot must start in open floor; the block belongs there too, but an original
    config.py may hide it (outside the maze, in a solid cell, under the robot)."""
    from simmer.config.maze import Block, Maze, robot_outline

    maze = Maze.from_settings(settings)
    block = Block.from_settings(settings)
    outline = robot_outline(settings)
    pose = Pose(*settings.robot_start_position, settings.robot_start_rotation)
    robot = np.empty_like(outline)
    place_polygon(outline, pose.x, pose.y, pose.heading, robot)
    robot_hit = polygon_hits_grid(robot, maze.hwall, maze.vwall, maze.solid, maze.cell)
    if robot_hit:
        found.errors.append(
            ConfigIssue(
                "robot_start_position",
                f"the robot at {_point(settings.robot_start_position)} overlaps a wall, a solid "
                "cell or the maze edge; put it in an open cell, e.g. "
                f"{_point(maze.open_cell_centre())}",
            )
        )
    where = f"the block at {_point(settings.block_position)}"
    if polygon_hits_grid(block.polygon, maze.hwall, maze.vwall, maze.solid, maze.cell):
        hidden = _hidden_place(maze, block.polygon)
        found.strict(
            "block_position",
            f"{where} overlaps a wall, a solid cell or the maze edge; put it inside an open cell",
            warning=f"{where} is {hidden}, so the robot can neither reach nor see it"
            if hidden
            else f"{where} overlaps a wall, a solid cell or the maze edge, so the robot cannot "
            "reach it as usual",
        )
    elif not robot_hit and polygons_overlap(robot, block.polygon):
        found.strict(
            "block_position",
            "the block overlaps the robot's start position",
            warning="the block overlaps the robot's start position, so the robot starts "
            "touching it, and a move that leaves it touching the block is undone",
        )


def check_project(settings: Settings) -> list[ConfigIssue]:
    """Zones on open cells of the maze, and a scenario that can be met (its start cell, block
    place and target zone), each mistake named by its key."""
    from simmer.config.maze import Maze
    from simmer.config.scenario import check_cell, draw_scenario
    from simmer.config.zones import Zones

    maze = Maze.from_settings(settings)
    z = settings.zones
    issues = []
    named = [("zones.loading", z.loading), ("zones.start", z.start)] + [
        (f"zones.dropoff.{name}", cells) for name, cells in (z.dropoff or {}).items()
    ]
    for key, cells in named:
        for i, cell in enumerate(cells or ()):
            try:
                check_cell(maze, cell, f"{key}[{i}]")
            except ScenarioError as exc:
                issues.append(ConfigIssue(exc.key, exc.message))
    if issues:
        return issues
    zones = Zones.from_settings(settings)
    try:  # the draws need a seed; any will do to find a setting that cannot be met
        draw_scenario(settings, maze, zones, lambda _: np.random.default_rng(0))
    except ScenarioError as exc:
        issues.append(ConfigIssue(exc.key, exc.message))
    return issues


def _hidden_place(maze: Maze, polygon: FloatArray) -> str | None:
    """``"outside the maze"`` or ``"inside a solid cell"`` if the polygon lies wholly there."""
    xs, ys = polygon[:, 0], polygon[:, 1]
    if xs.max() <= 0 or ys.max() <= 0 or xs.min() >= maze.width or ys.min() >= maze.height:
        return "outside the maze"
    cells = {(int(x // maze.cell), int(y // maze.cell)) for x, y in polygon}
    if len(cells) == 1:
        ((col, row),) = cells
        if 0 <= row < maze.rows and 0 <= col < maze.cols and maze.solid[row, col]:
            return "inside a solid cell"
    return None


# ----------------------------------------------------------------------------- messages


def _did_you_mean(name: str, candidates: list[str]) -> str:
    close = difflib.get_close_matches(name, candidates, n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _key_path(prefix: str, loc: tuple[int | str, ...]) -> str:
    path = prefix
    for part in loc:
        if isinstance(part, int):
            path += f"[{part}]"
        else:
            path = f"{path}.{part}" if path else str(part)
    return path


def _fields_at(model: type[BaseModel], loc: tuple[int | str, ...]) -> list[str]:
    """Field names of the (nested) model found by following ``loc`` from ``model``."""
    current: Any = model
    for part in loc:
        if isinstance(part, int):
            continue
        if not (isinstance(current, type) and issubclass(current, BaseModel)):
            return []
        field = current.model_fields.get(part)
        if field is None:
            return []
        current = _model_in(field.annotation)
    if isinstance(current, type) and issubclass(current, BaseModel):
        return list(current.model_fields)
    return []


def _model_in(annotation: Any) -> Any:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _shown(value: Any) -> str:
    """A configuration value as a message quotes it: short and on one line, however large or
    deeply nested it is."""
    return reprlib.repr(value)


def _number(value: float) -> str:
    """A number as a student writes it: 6, 0.25, 1,536, 3.6e+12."""
    if math.isfinite(value) and abs(value) < 1e15 and (value == int(value) or abs(value) >= 1e3):
        return f"{round(value):,}"
    return f"{value:.4g}"


def _rounded(value: float, *, up: bool) -> str:
    """A positive suggestion to 3 significant digits, rounded the safe way."""
    scale = 10.0 ** (math.floor(math.log10(value)) - 2)
    step = math.ceil if up else math.floor
    return _number(step(value / scale) * scale)


def _point(point: tuple[float, ...] | list[float]) -> str:
    """A point as written in the file: [6, 42]."""
    return "[" + ", ".join(_number(v) for v in point) + "]"


_WORDING = {
    "finite_number": "must be a finite number",
    "float_type": "must be a number",
    "float_parsing": "must be a number",
    "int_type": "must be a whole number",
    "int_parsing": "must be a whole number",
    "int_from_float": "must be a whole number",
    "bool_type": "must be true or false",
    "bool_parsing": "must be true or false",
    "string_type": "must be text in quotes",
    "tuple_type": "must be a list in brackets, like [1, 2]",
    "list_type": "must be a list in brackets, like [1, 2]",
    "greater_than": "must be greater than {gt}",
    "greater_than_equal": "must be {ge} or more",
    "less_than": "must be less than {lt}",
    "less_than_equal": "must be {le} or less",
    "too_short": "must have at least {min_length} values",
    "too_long": "must have at most {max_length} values",
    "literal_error": "must be {expected}",
}
"""What each kind of validation error means, in a student's words; each message ends with
", not <the value given>"."""


def _validation_message(error: ErrorDetails, model: type[BaseModel]) -> str:
    """One validation error as one line saying what the value must be."""
    kind, loc, given = error["type"], tuple(error["loc"]), _shown(error.get("input"))
    context = error.get("ctx", {})
    if kind == "value_error":  # a validator's own message already says what to do
        return str(context.get("error", error["msg"]))
    if kind in ("model_type", "model_attributes_type", "dict_type"):
        keys = " = ..., ".join(_fields_at(model, loc)) or "key"
        return f"must be a table like {{ {keys} = ... }}, not {given}"
    wording = _WORDING.get(kind)
    limits = {name: _bound(value) for name, value in context.items()}
    what = wording.format(**limits) if wording else error["msg"]
    return f"{what}, not {given}"


def _bound(value: Any) -> Any:
    """A limit as a file would write it: 86400, not 86400.0."""
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return int(value)
    return value


def _issues_from_validation(
    exc: ValidationError, prefix: str, model: type[BaseModel]
) -> list[ConfigIssue]:
    issues = []
    errors = exc.errors()
    failed = {tuple(error["loc"]) for error in errors}
    for error in errors:
        loc = tuple(error["loc"])
        kind = error["type"]
        if kind == "too_short" and any(len(f) > len(loc) and f[: len(loc)] == loc for f in failed):
            continue  # counts only the values that passed; the others are reported already
        if kind == "extra_forbidden":
            name = str(loc[-1])
            hint = _did_you_mean(name, _fields_at(model, loc[:-1]))
            message = f"unknown key{hint}; check its spelling or delete it"
        elif kind == "missing" and loc and isinstance(loc[-1], int):
            message = f"has too few values (value number {loc[-1] + 1} is missing)"
            loc = loc[:-1]
        elif kind == "missing":
            message = "required key is missing"
        else:
            message = _validation_message(error, model)
        issues.append(ConfigIssue(_key_path(prefix, loc), message))
    return issues
