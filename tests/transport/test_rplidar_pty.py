"""The virtual RPLidar: the ``rplidar`` package (from PyPI) reads it as it reads the real
scanner, in real time and under ``--program`` on the lockstep clock, and what it reads is the
simulator's own scans."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import rplidar  # the test extra's: the package Raspberry Pi programs read the RPLidar with

from link_support import run_program
from simmer import Simulation
from simmer.devices import Lidar
from simmer.options import RunOptions
from simmer.serve import serve
from simmer.transport.rplidar_pty import nodes
from simmer.world.events import Event, StepEvent

from helpers import default_data, make_sim, wait_for

READER = """\
import json, os, sys
{extra}from rplidar import RPLidar

lidar = RPLidar(sys.argv[1])
info, health = lidar.get_info(), lidar.get_health()
scans = []
for scan in lidar.iter_scans():
    scans.append(scan)
    if len(scans) == {count}:
        break
lidar.stop()
lidar.stop_motor()
lidar.disconnect()
with open(sys.argv[2], "w") as file:
    json.dump({{"info": info, "health": health, "scans": scans}}, file)
"""
MOTOR_LINE = (
    "import serial  # a pseudo-terminal has no DTR line: the motor follows SET_PWM there\n"
    "serial.Serial._update_dtr_state = lambda self: None\n"
)
"""The one line (and its import) a program started by hand adds (docs/devices.md)."""


def lidar_sim(**settings: Any) -> Simulation:
    data = default_data()
    data["sensors"]["l0"] = {"type": "lidar", "position": [0, 0]} | settings
    data["drives"]["r0"]["ang_velocity"] = 30
    return make_sim(data, seed=5)


def capture(sim: Simulation) -> dict[int, np.ndarray]:
    """Every scan the LiDAR makes, by number (an observer, as the virtual port's feed is)."""
    scans: dict[int, np.ndarray] = {}
    device = sim.robot.devices["l0"]
    assert isinstance(device, Lidar)

    def observe(event: Event) -> None:
        if isinstance(event, StepEvent):
            scans.setdefault(device.number, device.distances.copy())

    sim.add_observer(observe)
    return scans


def as_read(distances: np.ndarray) -> list[tuple[float, float]]:
    """A scan as the rplidar package reports it: (angle, mm) of each beam that returned,
    in 1/64 degree and 1/4 mm (the wire's units)."""
    beams = len(distances)
    angles = np.arange(beams) * (360.0 / beams)
    q2 = np.round(distances * 25.4 * 4.0)
    return [(round(a * 64) / 64, q / 4) for a, q in zip(angles, q2, strict=True) if q > 0]


def matches(read: list[list[float]], scans: dict[int, np.ndarray]) -> list[int]:
    """The numbers of the simulator's scans the read ones are, in order (fails if one is
    none of them)."""
    found = []
    for scan in read:
        got = [(angle, distance) for _quality, angle, distance in scan]
        same = [n for n, distances in scans.items() if as_read(distances) == got]
        assert same, f"a scan read ({len(got)} points) is none of the simulator's"
        found.append(same[0])
    return found


def test_nodes_are_slamtecs_five_byte_measurements() -> None:
    raw = nodes(np.array([0.0, 90.5, 359.0]), np.array([10.0, 0.0, 472.0]))
    assert len(raw) == 15
    decoded = [rplidar._process_scan(raw[i : i + 5]) for i in range(0, 15, 5)]
    assert decoded[0] == (True, 15, 0.0, 254.0)
    assert decoded[1] == (False, 0, 90.5, 0.0)  # no return: quality 0, distance 0
    assert decoded[2] == (False, 15, 359.0, 11988.75)


@pytest.mark.slow
def test_the_rplidar_package_reads_the_simulators_scans_under_program_and_repeats(
    tmp_path: Path,
) -> None:
    program = tmp_path / "read_lidar.py"
    program.write_text(READER.format(extra="", count=5), encoding="utf-8")
    results = []
    for run in range(2):
        sim = lidar_sim()
        sim.command("r0-3600")  # turning: every scan differs, and each is smeared
        scans = capture(sim)
        out = tmp_path / f"scans{run}.json"
        command = f'"{sys.executable}" "{program}" "$SIMMER_LIDAR_SERIAL" "{out}"'
        served = run_program(sim, f"sh -c '{command}'", lidar_serial=True)
        assert served.program_status == 0
        result = json.loads(out.read_text(encoding="utf-8"))
        assert result["info"]["model"] == 0x18
        assert result["health"] == ["Good", 0]
        read = result["scans"]
        assert len(read) == 5
        numbers = matches(read, scans)
        assert numbers == list(range(numbers[0], numbers[0] + 5))  # whole and consecutive
        results.append(read)
    assert results[0] == results[1]


@pytest.mark.slow
def test_a_program_started_by_hand_reads_it_in_real_time(tmp_path: Path) -> None:
    program = tmp_path / "read_lidar.py"
    program.write_text(READER.format(extra=MOTOR_LINE, count=4), encoding="utf-8")
    sim = lidar_sim()
    sim.command("r0-3600")
    scans = capture(sim)
    lines: list[str] = []
    options = RunOptions.free_ports(lidar_serial=True, speed=1.0, seconds=8.0)
    thread = threading.Thread(target=serve, args=(sim, options), kwargs={"echo": lines.append})
    thread.start()
    try:
        wait_for(lambda: any("virtual RPLidar" in line for line in lines), "the RPLidar's port")
        path = next(line for line in lines if "virtual RPLidar" in line).split()[2]
        out = tmp_path / "scans.json"
        done = subprocess.run(
            [sys.executable, str(program), path, str(out)],
            capture_output=True,
            text=True,
            timeout=60,
            check=False,
        )
        assert done.returncode == 0, done.stderr
    finally:
        thread.join()  # the run ends at its simulated-seconds limit
    read = json.loads(out.read_text(encoding="utf-8"))["scans"]
    numbers = matches(read, scans)
    assert len(numbers) == 4
    assert numbers == sorted(numbers)


def test_lidar_serial_without_a_lidar_says_what_to_add() -> None:
    from simmer.errors import SimmerError
    from simmer.runner import Runner
    from simmer.transport import Transports

    sim = make_sim()
    runner = Runner(sim)
    with pytest.raises(SimmerError, match='type = "lidar"'):
        Transports(runner.bus, sim.config, RunOptions.free_ports(lidar_serial=True))
    runner.bus.close()
