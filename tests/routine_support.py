"""The calibration routine driven straight on a simulation, in simulated time, into a tap's
run folder: the fit's and compare's quick tests (the slow one drives the real routine program
through a real tap: tests/calibrate/test_groundtruth.py)."""

from __future__ import annotations

from pathlib import Path

from simmer.calibrate.routine import HOLD, HOLDS, LEGS, READS, TURN, TURNS, plan
from simmer.config.models import SimConfig
from simmer.tap.decode import Exchange
from simmer.tap.folder import TapRecorder
from simmer.world.simulation import Simulation


def record_routine(robot: Simulation, team: SimConfig, folder: Path) -> None:
    """Run the routine's commands on ``robot`` and record them as a tap would, times being
    simulated seconds."""
    routine = plan(team)
    recorder = TapRecorder(folder, team, "simulated")

    def send(message: str) -> list[float]:
        replies = robot.command(message)
        at = recorder.start + robot.time
        recorder.record(Exchange(message, message.count(",") + 1, at, replies, at))
        return replies

    def stop() -> None:
        for _ in range(READS):
            send(routine.read_message)

    def move(drive: str, amount: float) -> None:
        send(f"{drive}-{amount:g}")
        robot.run_until_idle()
        send(f"{drive}-0")
        stop()

    stop()
    for _ in range(HOLDS):
        robot.step(round(HOLD * robot.config.settings.frame_rate))
        stop()
    for _ in range(LEGS):
        move(routine.drive, routine.leg)
        move(routine.drive, -routine.leg)
    assert routine.turn is not None
    assert routine.home is not None
    sensor, reading, per_inch = routine.home
    index = routine.read_message.split(",").index(sensor)
    now = sum(send(routine.read_message)[index] for _ in range(READS)) / READS
    if abs(now - reading) > 0.1:
        move(routine.drive, round((reading - now) / per_inch, 2))
    for _ in range(TURNS):
        move(routine.turn, TURN)
        move(routine.turn, -TURN)
    recorder.close(
        "the program exited",
        False,
        bytes_sent=0,
        bytes_received=0,
        stray=0,
        program=None,
        program_status=0,
    )


def record_short_run(robot: Simulation, team: SimConfig, folder: Path) -> None:
    """A few reads, one leg out and back, reads at each stop: recorded as a tap would."""
    routine = plan(team)
    recorder = TapRecorder(folder, team, "simulated")

    def send(message: str) -> None:
        replies = robot.command(message)
        at = recorder.start + robot.time
        recorder.record(Exchange(message, message.count(",") + 1, at, replies, at))

    def reads() -> None:
        for _ in range(4):
            send(routine.read_message)

    reads()
    for amount in (routine.leg, -routine.leg):
        send(f"{routine.drive}-{amount:g}")
        robot.run_until_idle()
        reads()
    recorder.close(
        "the program exited", False, bytes_sent=0, bytes_received=0, stray=0, program=None,
        program_status=0,
    )  # fmt: skip
