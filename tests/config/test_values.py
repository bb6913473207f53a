"""Configuration values that were accepted and then broke the run (issue 9): each is refused at
its own key, in one line a student can act on, before anything is built."""

from __future__ import annotations

import math
import sys
import threading
import types
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, Any, Union, get_args, get_origin

import pytest
from pydantic import BaseModel
from typer.testing import CliRunner

import simmer.config.maze
import simmer.config.simmer_py
from simmer.cli import app
from simmer.config import Settings, config_from_toml, load_config
from simmer.config.models import MAX_CELLS_PER_SIDE, MAX_TIMEOUT
from simmer.devices import Device, World, get_device_kind, register_device_kind
from simmer.errors import ConfigError
from simmer.world import Maze
from simmer.world.probe import probe_devices

from helpers import REPO, SIMMER_PY, default_data, make_config

Data = dict[str, Any]

BUILT_IN_DEVICES = {
    "motor": ("motors", "m0"),
    "drive": ("drives", "w0"),
    "ultrasonic": ("sensors", "u0"),
    "gyroscope": ("sensors", "g0"),
    "compass": ("sensors", "c0"),
    "infrared": ("sensors", "i0"),
}
"""One device of each built-in kind in :func:`every_kind_data`: kind -> (table, id)."""


def every_kind_data() -> Data:
    """The built-in default plus a gyroscope, a compass and an infrared sensor."""
    data = default_data()
    data["sensors"] |= {
        "g0": {"type": "gyroscope"},
        "c0": {"type": "compass"},
        "i0": {"type": "infrared", "position": [0, 1]},
    }
    return data


def issues_of(data: Data) -> list[tuple[str, str]]:
    """(key, message) of every issue ``data`` has; fails if it is accepted."""
    with pytest.raises(ConfigError) as caught:
        make_config(data)
    return [(issue.key, issue.message) for issue in caught.value.issues]


# ----------------------------------------------------------------------------- NaN and infinity


def sample(annotation: Any) -> Any:
    """A valid value of a numeric type (0 or a list of zeros), to fill the other places."""
    origin, args = get_origin(annotation), get_args(annotation)
    if origin is Annotated:
        return sample(args[0])
    if origin is tuple:
        items = [args[0]] * 3 if args[-1] is Ellipsis else list(args)
        return [sample(item) for item in items]
    return 0.0


def poisoned(annotation: Any, bad: float) -> Iterator[tuple[str, Any]]:
    """Each way to put ``bad`` in one number of a value of this type: (key suffix, value)."""
    origin, args = get_origin(annotation), get_args(annotation)
    if annotation is float:
        yield "", bad
    elif origin is Annotated:
        yield from poisoned(args[0], bad)
    elif origin in (Union, types.UnionType):
        yield from poisoned(next(arg for arg in args if arg is not type(None)), bad)
    elif origin is tuple:
        items = [args[0]] * 3 if args[-1] is Ellipsis else list(args)
        places = 1 if args[-1] is Ellipsis else len(items)  # one place of a list of any length
        for i in range(places):
            for suffix, value in poisoned(items[i], bad):
                filled = [value if j == i else sample(item) for j, item in enumerate(items)]
                yield f"[{i}]{suffix}", filled
    elif isinstance(annotation, type) and issubclass(annotation, BaseModel):
        for name, field in annotation.model_fields.items():
            for suffix, value in poisoned(field.annotation, bad):
                yield f".{name}{suffix}", {name: value}


def numeric_places() -> list[tuple[str, list[str | int], Any, str]]:
    """Every number of every setting and built-in device kind: (id, where the setting goes in
    the data, the field's value with NaN in it, the key the issue must name)."""
    places = []
    models: list[tuple[list[str | int], type[BaseModel], str]] = [([], Settings, "")]
    for kind, (group, device_id) in BUILT_IN_DEVICES.items():
        kind_cls = get_device_kind(kind)
        assert kind_cls is not None
        models.append(([group, device_id], kind_cls.Params, f"{group}.{device_id}."))
    for path, model, prefix in models:
        for name, field in model.model_fields.items():
            for suffix, value in poisoned(field.annotation, math.nan):
                key = f"{prefix}{name}{suffix}"
                places.append((key, [*path, name], value, key))
    return places


NUMERIC_PLACES = numeric_places()


def test_every_numeric_setting_is_covered() -> None:
    assert len(NUMERIC_PLACES) >= 27  # the places the mutation run found, and more
    keys = {key for _, _, _, key in NUMERIC_PLACES}
    assert {"drives.w0.velocity[1]", "sensors.u0.position[0]", "robot_outline[0][0]"} <= keys
    assert {"drives.w0.bias.rotation", "timeout", "ppi", "robot_start_rotation"} <= keys


def replace_nan(value: Any, bad: float) -> Any:
    """``value`` with its NaN replaced by ``bad``."""
    if isinstance(value, list):
        return [replace_nan(v, bad) for v in value]
    if isinstance(value, dict):
        return {k: replace_nan(v, bad) for k, v in value.items()}
    return bad if isinstance(value, float) and math.isnan(value) else value


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf], ids=["nan", "inf", "-inf"])
@pytest.mark.parametrize(
    ("path", "value", "key"), [pytest.param(p, v, k, id=i) for i, p, v, k in NUMERIC_PLACES]
)
def test_nan_and_infinity_are_refused_at_their_own_key(
    path: list[str | int], value: Any, key: str, bad: float
) -> None:
    data = every_kind_data()
    target: Any = data
    for part in path[:-1]:
        target = target[part]
    target[path[-1]] = replace_nan(value, bad)
    issues = issues_of(data)
    assert (key, f"must be a finite number, not {bad!r}") in issues, issues
    field_key = ".".join(str(part) for part in path)
    assert all(k.startswith(field_key) for k, _ in issues), issues  # nothing else is blamed


def test_toml_nan_and_inf_literals_are_refused(tmp_path: Path) -> None:
    text = (REPO / "src/simmer/data/default.toml").read_text(encoding="utf-8")
    assert text.count("velocity = [0, 6]") == 1
    text = "ppi = inf\nrobot_start_rotation = -inf\n" + text.replace(
        "velocity = [0, 6]", "velocity = [0, nan]"
    )
    with pytest.raises(ConfigError) as caught:
        config_from_toml(text, "nan.toml", tmp_path)
    rendered = caught.value.render().splitlines()
    velocity = text.splitlines().index("velocity = [0, nan]") + 1
    assert rendered == [  # each with its line, in the file's order
        "nan.toml:1: ppi: must be a finite number, not inf",
        "nan.toml:2: robot_start_rotation: must be a finite number, not -inf",
        f"nan.toml:{velocity}: drives.w0.velocity[1]: must be a finite number, not nan",
    ]


def test_config_py_float_nan_is_refused_on_its_line(tmp_path: Path) -> None:
    text = (SIMMER_PY / "lab_rover_quiet.py").read_text(encoding="utf-8")
    old = "robot_start_rotation = 180 "
    assert text.count(old) == 1
    path = tmp_path / "config.py"
    path.write_text(text.replace(old, "robot_start_rotation = float('nan') "), encoding="utf-8")
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    (issue,) = caught.value.issues
    assert issue.key == "robot_start_rotation"
    assert issue.message == "must be a finite number, not nan"
    lines = text.splitlines()
    assert issue.line == next(n for n, line in enumerate(lines, 1) if line.startswith(old))


# ----------------------------------------------------------------------------- sizes


@pytest.fixture
def no_floor_drawn(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail if a floor pattern is drawn: an oversize maze must be refused before that."""

    def refuse(*args: object) -> None:
        raise AssertionError(f"floor_pattern{args} was called")

    monkeypatch.setattr(simmer.config.maze, "floor_pattern", refuse)


@pytest.mark.usefixtures("no_floor_drawn")
@pytest.mark.parametrize(
    ("settings", "key", "fragment"),
    [
        ({"wall_segment_length": 1e6}, "floor_segment_length", "at most 1,000,000"),
        ({"wall_segment_length": 1e6}, "ppi", "at most 16,384 pixels a side"),
        ({"wall_segment_length": 1e308}, "wall_segment_length", "too large"),
        ({"wall_segment_length": math.inf}, "wall_segment_length", "finite"),
        ({"floor_segment_length": 1e-6}, "floor_segment_length", "floor_segment_length at least"),
        ({"ppi": math.inf}, "ppi", "finite"),
        ({"ppi": 1e300}, "ppi", "200 or less"),
        ({"ppi": 200}, "ppi", "make ppi at most 170"),
        ({"border_pixels": 2**63 - 1}, "border_pixels", "no room for the maze"),
        ({"robot_thickness": 1e308}, "robot_thickness", "12 or less"),
        ({"timeout": math.inf}, "timeout", "finite"),
        ({"timeout": 1e12}, "timeout", "86400 or less"),
        ({"port_rx": True}, "port_rx", "must be a whole number, not True"),
        ({"floor_seed": False}, "floor_seed", "must be a whole number, not False"),
    ],
    ids=lambda value: (
        "-".join(f"{k}={v}" for k, v in value.items()) if isinstance(value, dict) else None
    ),
)
def test_sizes_that_crashed_the_run_are_refused(settings: Data, key: str, fragment: str) -> None:
    data = default_data() | settings
    issues = issues_of(data)
    assert any(k == key and fragment in message for k, message in issues), issues
    assert "robot_start_position" not in {k for k, _ in issues}


class UnreadRow(list[int]):
    """A row of cells that fails the test if any of its cells is read."""

    def __iter__(self) -> Iterator[int]:
        raise AssertionError("a cell of the row was read")

    def __getitem__(self, index: Any) -> Any:
        raise AssertionError("a cell of the row was read")


def test_a_maze_of_10000_by_10000_cells_is_refused_at_once(no_floor_drawn: None) -> None:
    """At once: by its size, without reading a cell (the time it takes is in
    benchmarks/bench_cli.py)."""
    data = default_data()
    data["walls"] = [UnreadRow([1] * 10_000)] * 10_000  # one row, shared: cheap to build
    issues = issues_of(data)
    assert issues == [
        (
            "walls",
            "has 10,000 rows; at most 500 rows of 500 cells (the lab maze has 4 rows of 8), "
            "because every wall is stored and drawn, and a reading walks the maze cell by cell",
        )
    ]


def test_a_row_too_long_is_named() -> None:
    data = default_data()
    data["walls"] = [[1] * 8, [1] * (MAX_CELLS_PER_SIDE + 1)]
    assert [key for key, _ in issues_of(data)] == ["walls[1]"]


@pytest.mark.slow
def test_the_largest_maze_allowed_runs() -> None:
    data = default_data()
    side = MAX_CELLS_PER_SIDE
    data |= {  # a drawing of at most 16,384 pixels a side, a floor of at most 1e6 tiles
        "walls": [[1] * side] * side,
        "ppi": 2,
        "floor_segment_length": 12,
        "block_position": [18, 6],
    }
    config = make_config(data)
    maze = Maze.from_settings(config.settings)
    assert maze.solid.shape == (side, side)
    assert maze.floor_white.size <= 1_000_000


def test_a_maze_of_160_by_320_cells_as_the_original_built_is_accepted() -> None:
    data = default_data()
    data |= {"walls": [[1] * 320] * 160, "ppi": 4, "block_position": [18, 6]}
    config = make_config(data)  # the default floor: 640 x 1,280 tiles
    assert Maze.from_settings(config.settings).solid.shape == (160, 320)


def test_the_timeout_limit_fits_the_system_timers() -> None:
    assert threading.Lock().acquire(timeout=MAX_TIMEOUT)  # a free lock: no wait, but checked
    with pytest.raises(OverflowError):  # what `timeout = 1e12` did to the serial thread
        threading.Lock().acquire(timeout=1e12)


def test_a_file_too_large_to_be_a_configuration_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "huge.toml"
    path.write_text("# padding\n" * 200_000, encoding="utf-8")
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert "is 2,000,000 bytes" in caught.value.render()


def test_a_file_that_is_not_text_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "binary.toml"
    path.write_bytes(b"\xff\xfe\x00frame_rate = 60\n")
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert caught.value.render().startswith(f"{path}: cannot read the file: 'utf-8' codec")


def test_running_out_of_memory_while_loading_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "config.py"
    path.write_text("walls = [[1] * 10**6] * 10**6  # a student's list comprehension\n")

    def exhaust(*args: object) -> None:
        raise MemoryError

    monkeypatch.setattr(simmer.config.simmer_py, "load_simmer_py", exhaust)
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert caught.value.render() == (
        f"{path}: holds more data than fits in memory; no configuration needs that much"
    )


# ----------------------------------------------------------------------------- one clear line


def check(path: Path) -> tuple[int, str]:
    """Exit status and output of ``simmer check path``."""
    result = CliRunner().invoke(app, ["check", str(path)])
    assert result.exception is None or isinstance(result.exception, SystemExit)
    return result.exit_code, result.output


def test_deeply_nested_toml_array_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "deep.toml"
    path.write_text("walls = " + "[" * 5000 + "1" + "]" * 5000 + "\n", encoding="utf-8")
    status, output = check(path)
    assert status == 1
    assert output.splitlines()[1].startswith(f"  {path}: ")
    assert "nested too deeply" in output


@pytest.mark.slow
@pytest.mark.parametrize(
    "code",
    [
        "walls = 1\nfor _ in range(100000):\n    walls = [walls]\n",
        "walls = []\nwalls.append(walls)\n",
    ],
    ids=["deep", "cyclic"],
)
def test_deeply_nested_config_py_list_is_one_line(tmp_path: Path, code: str) -> None:
    path = tmp_path / "config.py"
    path.write_text(code, encoding="utf-8")
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert caught.value.render() == (
        f"{path}: lists or tables are nested too deeply to read; no setting nests more than 3"
    )


def test_a_plugin_calling_sys_exit_is_reported_not_obeyed(tmp_path: Path) -> None:
    (tmp_path / "quitter.py").write_text("import sys\n\nsys.exit(3)\n", encoding="utf-8")
    path = tmp_path / "robot.toml"
    path.write_text('plugins = ["quitter.py"]\n', encoding="utf-8")
    status, output = check(path)
    assert status == 1
    assert (
        f"{path}:1: plugins[0]: importing quitter.py failed at line 3: SystemExit: 3; a plug-in "
        "may not end the program: remove its sys.exit(), exit() or os._exit() call"
    ) in output.replace("\n  ", " ")


def test_a_simmer_device_file_calling_sys_exit_is_reported(tmp_path: Path) -> None:
    (tmp_path / "devices").mkdir()
    (tmp_path / "devices" / "quit.py").write_text("import sys\nsys.exit(3)\n", encoding="utf-8")
    path = tmp_path / "robot.toml"
    path.write_text(
        '[sensors.t0]\ntype = "simmer_device"\nmodule = "devices/quit.py"\nclass_name = "Q"\n',
        encoding="utf-8",
    )
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    (issue,) = caught.value.issues
    assert issue.key == "sensors.t0.class_name"
    assert "SystemExit: 3 (quit.py line 2)" in issue.message


def test_a_device_calling_sys_exit_is_reported_by_check() -> None:
    class Quitter(Device):
        def simulate(self, value: float, world: World) -> float:
            sys.exit(4)

    register_device_kind("test_quitter", Quitter, replace=True)
    data = default_data()
    data["sensors"]["q0"] = {"type": "test_quitter"}
    (issue,) = probe_devices(make_config(data))
    assert issue.key == "sensors.q0"
    assert "simulate(0.0) raised SystemExit: 4" in issue.message


# ----------------------------------------------------------------------------- the right key


def test_nan_rotation_is_not_blamed_on_the_start_position() -> None:
    data = default_data() | {"robot_start_rotation": math.nan}
    assert issues_of(data) == [("robot_start_rotation", "must be a finite number, not nan")]


def test_infinite_width_is_not_blamed_on_the_start_position() -> None:
    data = default_data() | {"robot_width": math.inf}
    del data["robot_outline"]
    assert issues_of(data) == [("robot_width", "must be a finite number, not inf")]


def test_nan_outline_is_one_issue_at_the_number() -> None:
    data = default_data() | {"robot_outline": [[0, 0], [1, math.nan], [1, 1]]}
    assert issues_of(data) == [("robot_outline[1][1]", "must be a finite number, not nan")]


def test_suggested_start_position_is_plain_numbers() -> None:
    data = default_data() | {"robot_start_position": [18, 30]}
    ((key, message),) = issues_of(data)
    assert key == "robot_start_position"
    assert message.startswith("the robot at [18, 30] overlaps")
    assert message.endswith("put it in an open cell, e.g. [6, 6]")


@pytest.mark.parametrize("position", [2.5, [1, 2, 3, 4], [1], "front"])
def test_a_position_of_the_wrong_shape_is_one_line(position: Any) -> None:
    data = default_data()
    data["sensors"]["u0"]["position"] = position
    shown = repr(position)
    assert issues_of(data) == [
        ("sensors.u0.position", f"must be [x, y] (or [x, y, height]) in inches, not {shown}")
    ]


def test_a_position_with_height_is_still_accepted() -> None:
    data = default_data()
    data["sensors"]["u0"]["position"] = [0, 2.5, 4]
    config = make_config(data)
    assert config.device("u0").params.position == (0.0, 2.5, 4.0)


def test_a_huge_walls_matrix_in_a_config_py_is_refused_before_it_is_copied(
    tmp_path: Path,
) -> None:
    path = tmp_path / "config.py"
    path.write_text("motors = {}\ndrives = {}\nsensors = {}\nwalls = [[1] * 10000] * 10000\n")
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    (issue,) = caught.value.issues
    assert (issue.key, issue.line) == ("walls", 4)
    assert "10,000 rows" in issue.message


@pytest.mark.parametrize("encoding", ["rot13", "hex", "utf-16", "utf-32", "base64", "nope"])
def test_str_encoding_that_cannot_carry_the_protocol_is_refused(encoding: str) -> None:
    data = default_data()
    data["str_encoding"] = encoding
    with pytest.raises(ConfigError) as caught:
        make_config(data)
    assert "str_encoding" in str(caught.value)
    assert "use 'utf-8' or 'ascii'" in str(caught.value)


@pytest.mark.parametrize("encoding", ["utf-8", "ascii", "latin-1", "cp1252"])
def test_text_encodings_that_write_ascii_as_ascii_are_accepted(encoding: str) -> None:
    data = default_data()
    data["str_encoding"] = encoding
    assert make_config(data).settings.str_encoding == encoding
