"""SimMeR config.py files: loading, stand-ins, user devices, errors with file and line."""

from __future__ import annotations

import logging
import math
import shutil
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer import Simulation
from simmer.cli import app
from simmer.config import load_config
from simmer.config.convert import convert_simmer_py
from simmer.errors import ConfigError

from helpers import LAB_SEQUENCE, SIMMER_PY, SIMMER_PY_FILES
from helpers import SIMMER_PY as FIXTURES

DEFAULT, QUIET, NOISY, WITH_DEVICE, TOF_DEVICE = ALL = SIMMER_PY_FILES
B0 = "'b0': Beacon(b0_info)"
NUM_RAYS = "'num_rays': 0"
DIRECTION = "'motor_direction': [1, 1]"
FRAMES = "info['frames']"
B0_ENTRY = "'b0': Beacon("
B0_INFO = "{'id': 'b0', 'position': [0, 0], 'rotation': 0, 'visible': True}"


def trace(sim: Simulation) -> list[tuple[float, ...]]:
    """The lab's dead-reckoning sequence: the pose (and every sensor reading) after each move."""
    sensors = ",".join(sim.robot.sensors)
    poses: list[tuple[float, ...]] = []
    for message in LAB_SEQUENCE:
        assert sim.command(message) == [math.inf], message
        assert sim.run_until_idle(max_seconds=60)
        poses.append((*sim.robot.pose, *sim.command(sensors)))
    return poses


def error_of(path: Path) -> ConfigError:
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    return caught.value


def line_of(path: Path, text: str) -> int:
    """1-based number of the first line of ``path`` containing ``text``."""
    lines = path.read_text(encoding="utf-8").splitlines()
    return next(n for n, line in enumerate(lines, 1) if text in line)


def edited(tmp_path: Path, source: Path, old: str, new: str) -> Path:
    """A copy of ``source`` in ``tmp_path`` with ``old`` replaced by ``new`` (once)."""
    text = source.read_text(encoding="utf-8")
    assert text.count(old) == 1, old
    target = tmp_path / "config.py"
    target.write_text(text.replace(old, new), encoding="utf-8")
    return target


# ----------------------------------------------------------------------------- loading


@pytest.mark.slow
@pytest.mark.parametrize("path", ALL, ids=lambda p: p.parent.name + "/" + p.name)
def test_fixture_loads_and_matches_its_converted_toml(path: Path, tmp_path: Path) -> None:
    toml = tmp_path / "robot.toml"
    convert_simmer_py(path, toml)
    original, converted = load_config(path), load_config(toml)
    assert original.source == str(path)
    assert trace(Simulation(original, seed=11)) == trace(Simulation(converted, seed=11))


def test_default_ids_come_from_the_dictionary_keys(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, logger="simmer.config.simmer_py"):
        config = load_config(DEFAULT)
    assert [d.id for d in config.devices] == [
        *("m0", "m1", "m2", "m3", "w0", "d0", "r0", "u0", "u1", "g0", "c0", "i0")
    ]
    assert config.device("g0").kind == "gyroscope"
    warnings = [r.getMessage() for r in caplog.records]
    assert len(warnings) == 4
    g0_id_line = line_of(DEFAULT, "g0_info = {") + 1
    assert f"default_config.py:{g0_id_line}: sensors['g0'] has 'id': 'u0'" in " ".join(warnings)


def test_settings_map_and_meaningless_keys_are_dropped() -> None:
    config = load_config(DEFAULT)
    s = config.settings
    assert s.robot_outline == ((-3, -3), (-3, 3), (3, 3), (3, -3))
    assert s.border_pixels == 36
    assert s.str_encoding == "ascii"
    w0 = config.device("w0").params
    assert w0.velocity == (0, 6)
    assert "ang_velocity" not in w0.model_fields_set
    assert "position" not in w0.model_fields_set
    assert config.device("r0").params.motors == ("m0", "m1", "m2", "m3")
    assert config.device("u0").params.outline == ((-1, -0.5), (-1, 0.5), (1, 0.5), (1, -0.5))


def test_lab_noise_lines_commented_in_and_out() -> None:
    quiet, noisy = load_config(QUIET), load_config(NOISY)
    assert quiet.device("w0").params.bias.rotation == 0
    assert quiet.device("w0").params.error.y == 0
    assert noisy.device("w0").params.bias.rotation == 0.2
    assert noisy.device("w0").params.error.y == 0.05
    assert noisy.device("r0").params.error.rotation == 0.02
    assert noisy.settings.simulate_list == ("u0", "u1", "u2", "u3")
    assert quiet.settings.simulate_list == ()
    assert trace(Simulation(quiet, seed=1)) != trace(Simulation(noisy, seed=1))


def test_nothing_leaks_into_the_process() -> None:
    modules_before = dict(sys.modules)
    path_before = list(sys.path)
    for path in ALL:
        load_config(path)
    assert sys.path == path_before
    for name in ("pygame", "pygame.math", "devices", "devices.motors", "config", "utilities"):
        assert sys.modules.get(name) is modules_before.get(name), name
    added = set(sys.modules) - set(modules_before)
    assert not [m for m in added if m.startswith(("devices", "config", "utilities", "pygame"))]


def test_a_real_module_named_like_a_stand_in_is_restored() -> None:
    import types

    marker = types.ModuleType("utilities")
    sys.modules["utilities"] = marker
    try:
        load_config(WITH_DEVICE)
        assert sys.modules["utilities"] is marker
    finally:
        del sys.modules["utilities"]


# ----------------------------------------------------------------------------- user devices


def test_user_device_runs_through_the_adapter() -> None:
    sim = Simulation(load_config(WITH_DEVICE), seed=5)
    assert sim.config.device("b0").kind == "simmer_device"
    sim.step(60)
    assert sim.command("b0-1") == [1.0]  # update() counted 60 frames; CONFIG.frame_rate is 60
    beacon = sim.robot.devices["b0"]
    pose = beacon.world_pose(sim.robot.pose)
    true_distance = math.hypot(sim.block.x - pose.x, sim.block.y - pose.y)
    readings = [sim.command("b0")[0] for _ in range(200)]
    assert min(readings) != max(readings)  # utilities.add_error adds noise
    assert abs(sum(readings) / len(readings) - true_distance) < 2.0


def test_user_device_is_seeded() -> None:
    first = Simulation(load_config(WITH_DEVICE), seed=9)
    second = Simulation(load_config(WITH_DEVICE), seed=9)
    assert [first.command("b0") for _ in range(5)] == [second.command("b0") for _ in range(5)]


def test_v11_layout_config_folder_and_config_config_import(tmp_path: Path) -> None:
    (tmp_path / "config").mkdir()
    shutil.copytree(FIXTURES / "with_device" / "devices", tmp_path / "devices")
    beacon = tmp_path / "devices" / "beacon.py"
    text = beacon.read_text(encoding="utf-8")
    beacon.write_text(text.replace("import config as CONFIG", "import config.config as CONFIG"))
    config_py = tmp_path / "config" / "config.py"
    shutil.copy(WITH_DEVICE, config_py)
    sim = Simulation(load_config(config_py), seed=2)
    sim.step(30)
    assert sim.command("b0-1") == [0.5]


def test_user_device_among_motors_says_what_to_change(tmp_path: Path) -> None:
    path = edited(
        tmp_path,
        WITH_DEVICE,
        "    'b0': Beacon(b0_info)   # the user's own device\n",
        "",
    )
    text = path.read_text(encoding="utf-8")
    path.write_text(
        text.replace(
            "    'm1': MotorSimple(m1_info)\n",
            "    'm1': MotorSimple(m1_info),\n    'b0': Beacon(" + B0_INFO + ")\n",
        )
    )
    shutil.copytree(FIXTURES / "with_device" / "devices", tmp_path / "devices")
    error = error_of(path)
    assert "only as sensors" in str(error)
    assert f"{path}:{line_of(path, B0_ENTRY)}" in str(error)


def test_user_class_without_simulate_says_what_to_change(tmp_path: Path) -> None:
    shutil.copytree(FIXTURES / "with_device" / "devices", tmp_path / "devices")
    beacon = tmp_path / "devices" / "beacon.py"
    text = beacon.read_text(encoding="utf-8")
    beacon.write_text(
        text.replace(
            "def simulate(self, value: float, environment: dict)",
            "def measure(self, value, environment)",
        )
    )
    path = tmp_path / "config.py"
    shutil.copy(WITH_DEVICE, path)
    error = error_of(path)
    assert "def simulate(self, value, environment)" in str(error)
    assert f"{path}:{line_of(path, B0)}" in str(error)


# ----------------------------------------------------------------------------- errors


def test_missed_comma_after_uncommenting_a_line(tmp_path: Path) -> None:
    path = edited(
        tmp_path,
        QUIET,
        "    # 'bias': {'x': 0, 'y': 0, 'rotation': 0.2},",
        "    'bias': {'x': 0, 'y': 0, 'rotation': 0.2},",
    )
    error = error_of(path)
    line = line_of(path, DIRECTION)
    assert len(error.issues) == 1
    assert f"{path}:{line}: a comma is missing" in str(error)
    assert "comment a line out or back in" in str(error)


def test_other_syntax_error_names_file_and_line(tmp_path: Path) -> None:
    path = edited(tmp_path, QUIET, "robot_width = 6 ", "robot_width = 6) ")
    error = error_of(path)
    assert str(error).startswith(f"{path}:{line_of(path, 'robot_width = 6)')}: Python cannot read")


def test_missing_required_dictionary(tmp_path: Path) -> None:
    path = edited(
        tmp_path,
        QUIET,
        "drives = {\n    'w0': Drive(w0_info),\n    'r0': Drive(r0_info)\n}\n",
        "",
    )
    error = error_of(path)
    assert [i.key for i in error.issues] == ["drives"]
    line = line_of(path, "'m1': MotorSimple(m1_info)") + 2  # just after the motors dictionary
    assert f"{path}:{line}: drives: is missing" in str(error)
    assert "add `drives = {}`" in str(error)


def test_exception_while_running_names_file_and_line(tmp_path: Path) -> None:
    path = edited(
        tmp_path,
        QUIET,
        "'motors': [motors['m0'], motors['m1']],\n    'motor_direction': [1, -1]",
        "'motors': [motors['m0'], motors['m2']],\n    'motor_direction': [1, -1]",
    )
    error = error_of(path)
    line = line_of(path, "motors['m2']")
    assert f"{path}:{line}: running the configuration failed: KeyError: 'm2'" in str(error)
    assert "only list motors defined in the motors dictionary" in str(error)


def test_missing_module_names_file_and_line(tmp_path: Path) -> None:
    path = edited(
        tmp_path,
        QUIET,
        "from devices.drive import Drive\n",
        "from devices.drive import Drive\nimport shapely\n",
    )
    error = error_of(path)
    line = line_of(path, "import shapely")
    assert f"{path}:{line}: running the configuration failed: ModuleNotFoundError" in str(error)


def test_exception_in_a_user_device_names_its_file(tmp_path: Path) -> None:
    shutil.copytree(FIXTURES / "with_device" / "devices", tmp_path / "devices")
    beacon = tmp_path / "devices" / "beacon.py"
    text = beacon.read_text(encoding="utf-8")
    beacon.write_text(text.replace("self.frames = 0", "self.frames = info['frames']"))
    path = tmp_path / "config.py"
    shutil.copy(WITH_DEVICE, path)
    error = error_of(path)
    assert f"{path}:{line_of(path, B0)}: running" in str(error)
    assert f"KeyError: 'frames' (devices/beacon.py line {line_of(beacon, FRAMES)})" in str(error)


def test_validation_messages_carry_config_py_lines(tmp_path: Path) -> None:
    path = edited(
        tmp_path, QUIET, "    'rotation': -90,\n", "    'rotation': -90,\n    'num_rays': 0,\n"
    )
    error = error_of(path)
    assert f"{path}:{line_of(path, NUM_RAYS)}: sensors.u1.num_rays:" in str(error)


# ----------------------------------------------------------------------------- simmer check


@pytest.mark.parametrize("path", ALL, ids=lambda p: p.parent.name + "/" + p.name)
def test_check_accepts_each_fixture(path: Path) -> None:
    result = CliRunner().invoke(app, ["check", str(path)])
    assert result.exit_code == 0, result.output
    assert "OK" in result.output


def test_check_reports_a_broken_config_without_traceback(tmp_path: Path) -> None:
    path = edited(
        tmp_path,
        QUIET,
        "    # 'bias': {'x': 0, 'y': 0, 'rotation': 0.2},",
        "    'bias': {'x': 0, 'y': 0, 'rotation': 0.2},",
    )
    result = CliRunner().invoke(app, ["check", str(path)])
    assert result.exit_code == 1
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    text = " ".join(result.output.split())
    assert f"{path}:{line_of(path, DIRECTION)}" in text


def test_toml_simmer_device_needs_file_and_class(tmp_path: Path) -> None:
    shutil.copytree(FIXTURES / "with_device" / "devices", tmp_path / "devices")
    toml = tmp_path / "robot.toml"
    toml.write_text(
        '[sensors.t0]\ntype = "simmer_device"\n\n'
        '[sensors.t1]\ntype = "simmer_device"\nmodule = "devices/beacon.py"\n'
        'class_name = "Becon"\n',
        encoding="utf-8",
    )
    text = str(error_of(toml))
    assert "sensors.t0.module: missing" in text
    assert "sensors.t0.class_name: missing" in text
    assert "sensors.t1.class_name: beacon.py has no class 'Becon'" in text


def test_misspelt_setting_is_reported(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    path = edited(tmp_path, QUIET, "robot_width = 6 ", "robot_widht = 6 ")
    with caplog.at_level(logging.WARNING, logger="simmer.config.simmer_py"):
        load_config(path)
    line = line_of(path, "robot_widht")
    assert (
        f"config.py:{line}: 'robot_widht' is not a SimMeR setting (did you mean 'robot_width'?)"
        in (caplog.text)
    )


def test_syntax_error_in_a_user_device_names_its_file(tmp_path: Path) -> None:
    shutil.copytree(FIXTURES / "with_device" / "devices", tmp_path / "devices")
    beacon = tmp_path / "devices" / "beacon.py"
    text = beacon.read_text(encoding="utf-8")
    beacon.write_text(text.replace("self.frames = 0", "self.frames = = 0"))
    path = tmp_path / "config.py"
    shutil.copy(WITH_DEVICE, path)
    error = str(error_of(path))
    assert (
        f"{path}:{line_of(path, 'from devices.beacon')}: running the configuration failed" in error
    )
    assert f"(devices/beacon.py line {line_of(beacon, 'self.frames = = 0')})" in error


def test_exit_in_config_is_an_error_not_an_exit(tmp_path: Path) -> None:
    path = edited(tmp_path, QUIET, "robot_width = 6 ", "import sys; sys.exit(3)\nrobot_width = 6 ")
    assert f"{path}:{line_of(path, 'sys.exit')}: running" in str(error_of(path))


def test_a_config_py_run_answers_nan_to_digits_outside_ascii() -> None:
    sim = Simulation(load_config(SIMMER_PY / "lab_rover_quiet.py"))
    assert math.isnan(sim.command("w0-６")[0])
    assert sim.command("w0-6") == [math.inf]
