"""A device whose own code raises is switched off; the simulator keeps serving (and `simmer check`
finds such code before a run)."""

from __future__ import annotations

import logging
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from link_support import serving
from simmer import Simulation
from simmer.cli import app
from simmer.client import connect
from simmer.devices import Device, DeviceParams, Shape, World, register_device_kind
from simmer.errors import CommandError, ConfigIssue
from simmer.ui.bridge import Bridge
from simmer.ui.hud import ALARM, BOX, COMMANDS_X, paint_hud
from simmer.ui.render import RecordingRenderer
from simmer.ui.scene import PANEL_HEIGHT, default_window_size
from simmer.world.events import Event, StepEvent
from simmer.world.probe import probe_devices

from helpers import SIMMER_PY, default_data, make_config, make_sim

pytestmark = pytest.mark.timeout(60)


def _fail() -> float:
    return 1 / 0


HERE = Path(__file__).name
"""This file's name, as the simulation names the line of a device's code."""
FAIL_LINE = _fail.__code__.co_firstlineno + 1
REASON = f"ZeroDivisionError: division by zero ({HERE} line {FAIL_LINE})"
"""What the simulation says about every faulty device below: the user's own line."""


def faulty_kind(name: str, where: str) -> str:
    """Register (as ``name``) a sensor reading 7 whose ``where`` method raises: "simulate",
    "update", or "shapes" (once it has been read, like a sensor drawing its last reading)."""

    class Faulty(Device):
        read = False

        def simulate(self, value: float, world: World) -> float:
            if where == "simulate":
                _fail()
            self.read = True
            return 7.0

        def update(self, world: World) -> None:
            if where == "update":
                _fail()

        def shapes(self, world: World) -> list[Shape]:
            if where == "shapes" and self.read:
                _fail()
            return []

    register_device_kind(name, Faulty, replace=True)
    return name


def t0_records(caplog: pytest.LogCaptureFixture) -> list[logging.LogRecord]:
    """Log records above DEBUG that mention device t0."""
    return [r for r in caplog.records if r.levelno > logging.DEBUG and "t0" in r.getMessage()]


@pytest.mark.parametrize(
    ("where", "listed", "during", "first_read"),
    [
        ("simulate", False, "command 't0'", math.nan),
        ("update", False, "update()", math.nan),
        ("shapes", False, "shapes()", 7.0),
        ("simulate", True, "simulate() for simulate_list", math.nan),
    ],
    ids=["simulate", "update", "shapes", "simulate_list"],
)
def test_faulty_device_is_switched_off_and_the_simulator_keeps_serving(
    where: str, listed: bool, during: str, first_read: float, caplog: pytest.LogCaptureFixture
) -> None:
    data = default_data()
    data["sensors"]["t0"] = {"type": faulty_kind(f"test_faulty_{where}_{listed}", where)}
    if listed:
        data["simulate_list"] = [*data["simulate_list"], "t0"]
    sim = Simulation(make_config(data))
    reference = make_sim()  # the same robot without t0: what u1 must read
    bridge = Bridge(sim)

    def draw_each_step(event: Event) -> None:  # the window's hook, in the simulation's thread
        if isinstance(event, StepEvent):
            bridge.sync()

    sim.add_observer(draw_each_step)
    caplog.set_level(logging.DEBUG, logger="simmer")
    with serving(sim, speed=None) as (_, link), connect(port=link.stream.port) as client:
        assert client.send("w0-1") == [math.inf]
        client.wait_idle()
        first = client.send("u1,t0,m0")
        assert client.send("w0-1") == [math.inf]  # the loop goes on stepping
        client.wait_idle()
        second = client.send("u1,t0,m0,t0")
    expected = []
    for _ in range(2):
        reference.command("w0-1")
        reference.run_until_idle()
        expected.append(reference.command("u1,m0"))
    assert first[0] == pytest.approx(expected[0][0])  # float32 replies
    assert first[1] == pytest.approx(first_read, nan_ok=True)
    assert first[2] == pytest.approx(expected[0][1])
    assert second[0] == pytest.approx(expected[1][0])
    assert math.isnan(second[1])
    assert second[2] == pytest.approx(expected[1][1])
    assert math.isnan(second[3])
    assert sim.robot.pose.y == pytest.approx(42.0 - 2.0)
    assert sim.time > 2 / 6  # two 1 in drives at 6 in/s

    assert dict(sim.switched_off) == {"t0": REASON}
    assert bridge.latest.switched_off == (("t0", REASON),)
    records = t0_records(caplog)
    assert len(records) == 1, [r.getMessage() for r in records]
    record = records[0]
    assert record.levelno == logging.ERROR
    assert during in record.getMessage()
    assert REASON in record.getMessage()
    assert record.exc_info is not None
    assert record.exc_info[0] is ZeroDivisionError

    sim.reset()
    assert dict(sim.switched_off) == {}
    after_reset = sim.command("t0")[0]
    if where == "simulate":
        assert math.isnan(after_reset)  # its code still raises: switched off again
    else:
        assert after_reset == 7.0
    bridge.close()


def test_switched_off_device_is_shown_in_red_on_the_hud() -> None:
    data = default_data()
    data["sensors"]["t0"] = {"type": faulty_kind("test_faulty_hud", "simulate")}
    sim = Simulation(make_config(data))
    bridge = Bridge(sim)
    assert math.isnan(sim.command("t0")[0])
    bridge.sync()
    r = RecordingRenderer()
    paint_hud(r, bridge.latest)
    red = [args[0] for args in r.of("text") if args[2] == ALARM]
    assert red == [f"t0 switched off: {REASON}"]
    bridge.close()


def test_the_switched_off_box_stays_in_the_panel_above_the_maze() -> None:
    data = default_data()
    data["sensors"]["t0"] = {"type": faulty_kind("test_faulty_box", "simulate")}
    data["sensors"]["t1"] = {"type": faulty_kind("test_faulty_box_2", "simulate")}
    sim = Simulation(make_config(data))
    bridge = Bridge(sim)
    sim.command("t0")
    sim.command("t1")
    bridge.sync()
    width = default_window_size(sim)[0]
    for room in (width, 1000):  # a narrower window cuts the lines instead
        r = RecordingRenderer()
        paint_hud(r, bridge.latest, room)
        (box,) = [args[0] for args in r.of("rect") if args[1] == BOX]
        x, y, w, h = box
        assert y >= 0
        assert y + h <= PANEL_HEIGHT  # never over the maze
        assert x >= COMMANDS_X - 10  # beside the time, pose and outcome
        assert x + w <= room
        red = [args[0] for args in r.of("text") if args[2] == ALARM]
        assert [line[:2] for line in red] == ["t0", "t1"]
        if room == width:
            assert red[0] == f"t0 switched off: {REASON}"
        else:
            assert str(red[0]).endswith("...")
    bridge.close()


def test_a_fault_does_not_cost_the_other_devices_their_step() -> None:
    data = default_data()
    data["sensors"]["t0"] = {"type": faulty_kind("test_faulty_before_gyro", "update")}
    data["sensors"]["g0"] = {"type": "gyroscope", "bias": 0, "error": 0}
    sim = Simulation(make_config(data))
    assert list(sim.robot.devices).index("t0") < list(sim.robot.devices).index("g0")
    sim.command("r0-90")
    assert sim.run_until_idle()
    assert "t0" in sim.switched_off
    assert sim.command("g0") == pytest.approx([90.0])


def test_command_error_is_a_bad_command_not_a_fault(caplog: pytest.LogCaptureFixture) -> None:
    class Picky(Device):
        def simulate(self, value: float, world: World) -> float:
            if value == 0:
                raise CommandError("p0 needs a channel number")
            return value

    register_device_kind("test_picky", Picky, replace=True)
    data = default_data()
    data["sensors"]["p0"] = {"type": "test_picky"}
    data["simulate_list"] = ["p0", "u0"]
    sim = Simulation(make_config(data))
    with caplog.at_level(logging.WARNING, logger="simmer"):
        sim.step(3)
        replies = [sim.command("p0")[0], sim.command("p0")[0], sim.command("p0-2")[0]]
    assert math.isnan(replies[0])
    assert math.isnan(replies[1])
    assert replies[2] == 2.0
    assert dict(sim.switched_off) == {}
    messages = [r.getMessage() for r in caplog.records]
    assert messages == [
        "simulate_list: p0 is no longer read every step: p0 needs a channel number",
        "bad command 'p0': p0 needs a channel number",
        "bad command 'p0': p0 needs a channel number",
    ]


SLOPPY = '''\
"""Two device kinds with a bug each."""
from simmer.devices import Device, World, register_device_kind


class Sloppy(Device):
    def simulate(self, value: float, world: World) -> float:
        return 1.0

    def update(self, world: World) -> None:
        self.smooth_reading()


class Scribble(Device):
    def simulate(self, value: float, world: World) -> float:
        return 1.0

    def shapes(self, world: World) -> list:
        return list(self.rays)


register_device_kind("test_check_sloppy", Sloppy)
register_device_kind("test_check_scribble", Scribble)
'''


@pytest.mark.slow
def test_check_calls_each_device_and_names_the_users_line(tmp_path: Path) -> None:
    (tmp_path / "devices").mkdir()
    (tmp_path / "devices" / "sloppy.py").write_text(SLOPPY, encoding="utf-8")
    path = tmp_path / "robot.toml"
    path.write_text(
        'plugins = ["devices/sloppy.py"]\n\n'
        '[sensors.s0]\ntype = "test_check_sloppy"\n\n'
        '[sensors.s1]\ntype = "test_check_scribble"\n\n'
        '[sensors.s2]\ntype = "test_check_scribble"\nposition = [1, 0]\n',
        encoding="utf-8",
    )
    done = subprocess.run(
        [sys.executable, "-m", "simmer", "check", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 1, done.stdout + done.stderr
    text = " ".join(done.stderr.split())
    assert "Traceback" not in text
    lines = SLOPPY.splitlines()
    update_line = lines.index("        self.smooth_reading()") + 1
    shapes_line = lines.index("        return list(self.rays)") + 1
    assert f"3 problems in {path}:" in text
    assert (
        f"{path}:3: sensors.s0: update() raised AttributeError: 'Sloppy' object has no attribute "
        f"'smooth_reading' (devices/sloppy.py line {update_line}); a name used on that line does "
        "not exist"
    ) in text
    for device_id, line in (("s1", 6), ("s2", 9)):  # each with its table's line
        assert (
            f"{path}:{line}: sensors.{device_id}: shapes() raised AttributeError: 'Scribble' "
            f"object has no attribute 'rays' (devices/sloppy.py line {shapes_line})"
        ) in text


def test_probe_names_a_device_whose_constructor_raises() -> None:
    class Fragile(Device):
        def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator):
            super().__init__(device_id, params, rng)
            self.window = int("ten")

        def simulate(self, value: float, world: World) -> float:
            return 1.0

    register_device_kind("test_probe_fragile", Fragile, replace=True)
    data = default_data()
    data["sensors"]["f0"] = {"type": "test_probe_fragile"}
    line = Fragile.__init__.__code__.co_firstlineno + 2
    assert probe_devices(make_config(data)) == [
        ConfigIssue(
            "sensors.f0",
            "building the device raised ValueError: invalid literal for int() with base 10: "
            f"'ten' ({HERE} line {line}); fix the code on that line; run unfixed, "
            "the device is switched off and its commands answer NaN",
        )
    ]


def test_check_finds_a_missing_helper_in_a_simmer_style_device(tmp_path: Path) -> None:
    shutil.copytree(SIMMER_PY / "with_device", tmp_path / "robot")
    beacon = tmp_path / "robot" / "devices" / "beacon.py"
    source = beacon.read_text(encoding="utf-8")
    assert "self.frames += 1" in source
    beacon.write_text(
        source.replace("self.frames += 1", "self.frames = utilities.count_frames(self.frames)"),
        encoding="utf-8",
    )
    line = next(
        i for i, text in enumerate(beacon.read_text().splitlines(), 1) if "count_frames" in text
    )
    result = CliRunner().invoke(app, ["check", str(tmp_path / "robot" / "config.py")])
    assert result.exit_code == 1, result.output
    text = " ".join(result.output.split())
    assert "config.py: sensors.b0: update() raised AttributeError" in text
    assert "not 'count_frames'" in text
    assert f"(devices/beacon.py line {line})" in text


def test_probe_calls_no_drive() -> None:
    class Tripwire(Device):
        category = "drive"

        def simulate(self, value: float, world: World) -> float:
            raise AssertionError("a check must not start a drive")

    register_device_kind("test_probe_tripwire", Tripwire, replace=True)
    data = default_data()
    data["drives"]["x0"] = {"type": "test_probe_tripwire"}
    config = make_config(data)
    assert "x0" in Simulation(config).robot.devices
    assert probe_devices(config) == []


def test_a_device_calling_sys_exit_is_switched_off_not_the_simulator() -> None:
    class Quitter(Device):
        def simulate(self, value: float, world: World) -> float:
            raise SystemExit(0)

    register_device_kind("test_quitter", Quitter, replace=True)
    data = default_data()
    data["sensors"]["q0"] = {"type": "test_quitter"}
    sim = Simulation(make_config(data))
    replies = sim.command("q0,u1")
    assert math.isnan(replies[0])
    assert replies[1] == pytest.approx(3.5)
    assert "q0" in sim.switched_off
