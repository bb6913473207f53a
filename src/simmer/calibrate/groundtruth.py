"""Ground truth for the calibration: a "robot" that is a simulator with hidden noise settings,
driven by the calibration routine through ``simmer tap``, then fitted and compared.

:func:`trial` draws the hidden settings (:func:`hidden_settings`, from the trial's number),
serves the robot's serial port from a simulation with them (its own loop thread, real time, as
``simmer run --serial`` would), runs the routine program through a :class:`~simmer.tap.session.
Tap` into a run folder, fits it with the team's configuration (the same robot, its noise
unknown) and says which hidden settings fell inside their intervals, and how many of the
run's readings fell inside the band the fitted configuration predicts (each seed drawing the
fitted settings from their intervals, as ``simmer compare --fitted`` does). ``benchmarks/
calibration_recovery.py`` runs twenty; a slow test runs one.
"""

from __future__ import annotations

import sys
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from simmer.calibrate.compare import compare
from simmer.calibrate.fit import Calibration, calibrate, fitted_overrides, intervals
from simmer.calibrate.routine import HOLD, plan, routine_program
from simmer.config.models import SimConfig
from simmer.config.overrides import with_overrides

GYRO = {"type": "gyroscope", "error": 0.02, "bias": 0.0}
"""The gyroscope the ground-truth robot carries (its error known to the team)."""


def team_config(base: SimConfig) -> SimConfig:
    """The team's configuration: ``base`` with a gyroscope ``g0`` and every noise setting
    the routine fits at 0 (unknown)."""
    return with_overrides(base, {"sensors.g0": dict(GYRO)})


def hidden_settings(number: int, config: SimConfig) -> dict[str, float]:
    """The settings a trial's robot hides, drawn from the trial's number: each straight and
    turning drive's bias (-5% to 5%) and error (0.5% to 4%) along its motion, each ultrasonic
    sensor's error (0.5% to 4%) and the gyroscope's drift (-0.3 to 0.3 deg/s)."""
    rng = np.random.default_rng([33, number])
    routine = plan(config)
    hidden: dict[str, float] = {}
    drive_axis = "y"
    hidden[f"drives.{routine.drive}.bias.{drive_axis}"] = float(rng.uniform(-0.05, 0.05))
    hidden[f"drives.{routine.drive}.error.{drive_axis}"] = float(rng.uniform(0.005, 0.04))
    if routine.turn is not None:
        hidden[f"drives.{routine.turn}.bias.rotation"] = float(rng.uniform(-0.05, 0.05))
        hidden[f"drives.{routine.turn}.error.rotation"] = float(rng.uniform(0.005, 0.04))
    for sensor in routine.sensors:
        hidden[f"sensors.{sensor}.error"] = float(rng.uniform(0.005, 0.04))
    for gyro in routine.gyros:
        hidden[f"sensors.{gyro}.bias"] = float(rng.uniform(-0.3, 0.3))
    return hidden


@dataclass(frozen=True)
class Trial:
    """One trial's result."""

    number: int
    hidden: dict[str, float]
    calibration: Calibration
    covered: dict[str, bool]
    inside: float
    """Fraction of the run's readings inside the fitted configuration's band."""
    inside_point: float | None
    """The same with the fitted values alone (no draws from their intervals), if asked."""
    folder: Path

    def as_dict(self) -> dict[str, Any]:
        """For a benchmark's JSON."""
        return {
            "trial": self.number,
            "inside": self.inside,
            "inside_point": self.inside_point,
            "settings": {
                key: {
                    "hidden": self.hidden[key],
                    "fitted": (e := self.calibration.value(key)).value,
                    "low": e.low,
                    "high": e.high,
                    "covered": self.covered[key],
                }
                for key in self.hidden
            },
        }


def trial(
    number: int,
    folder: Path,
    base: SimConfig,
    seeds: int = 100,
    *,
    point: bool = False,
    hold: float = HOLD,
) -> Trial:
    """Run one trial into ``folder`` (a new folder) and fit it (see the module doc); with
    ``point``, also compare with the fitted values alone; ``hold``: the routine's holds."""
    from simmer.options import RunOptions
    from simmer.runner import Runner
    from simmer.tap.folder import load_tap_run
    from simmer.tap.session import Tap
    from simmer.transport import Transports
    from simmer.world.simulation import Simulation

    team = team_config(base)
    hidden = hidden_settings(number, team)
    robot = Simulation(with_overrides(team, hidden), seed=number)
    folder.mkdir(parents=True)
    program = folder / "calibration_routine.py"
    program.write_text(routine_program(team, plan(team), hold=hold))
    runner = Runner(robot, speed=1.0, keep_time=True)  # a real robot's clock never skips
    stop = threading.Event()
    link = Transports(runner.bus, robot.config, RunOptions.free_ports(serial=True))
    with link:
        thread = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
        thread.start()
        try:
            assert link.serial is not None
            tap = Tap(team, link.serial.path, folder / "run")
            tap.run([sys.executable, str(program), "{port}"])
        finally:
            stop.set()
            thread.join()
            runner.bus.close()
    run = load_tap_run(folder / "run")
    calibration = calibrate(run, team)
    covered = {key: calibration.value(key).covers(value) for key, value in hidden.items()}
    fitted = with_overrides(team, fitted_overrides(calibration))
    inside = compare(run, fitted, seeds=seeds, intervals=intervals(calibration)).inside_fraction
    inside_point = compare(run, fitted, seeds=seeds).inside_fraction if point else None
    return Trial(number, hidden, calibration, covered, inside, inside_point, folder)
