"""Dead reckoning to the block (MIE444 Lab 1): drive the lab's fixed sequence and print the four
ultrasonic readings after each move.

Start the simulator first (``simmer run``), then, in a second terminal with SimMeR's
environment active (the README's Quick start says how), run
``python dead_reckoning.py`` in the folder ``simmer new`` made (in SimMeR's own folder:
``python examples/dead_reckoning.py``).
With perfect drives the rover ends facing the block; switch noise on in the configuration and
watch it miss.
"""

from __future__ import annotations

import argparse
import math

from simmer.client import Client, connect
from simmer.errors import ClientError

SEQUENCE = [
    ("w0", 36), ("r0", 90), ("w0", 36), ("r0", 90), ("w0", 12),
    ("r0", -90), ("w0", 24), ("r0", -90), ("w0", 6), ("r0", 720),
]  # fmt: skip
SENSORS = "u0,u1,u2,u3"


def show(values: list[float]) -> str:
    """Format the four readings on one line."""
    return "  ".join(f"u{i} {v:6.2f}" for i, v in enumerate(values))


def drive_sequence(robot: Client) -> list[list[float]]:
    """Drive the sequence with a connected client; returns the readings taken after each move.

    Also a sweep's policy (``policy = "dead_reckoning:drive_sequence"``): the same moves run
    in-process, without a program or a socket per run.
    """
    readings = []
    print("start      " + show(robot.send(SENSORS)))
    for drive, amount in SEQUENCE:
        if not math.isinf(robot.drive(drive, amount)):
            raise SystemExit(f"{drive} {amount} was not accepted (a drive is still moving?)")
        robot.wait_idle(drive)
        values = robot.send(SENSORS)
        readings.append(values)
        print(f"{drive} {amount:5g}   " + show(values))
    return readings


def main(argv: list[str] | None = None) -> list[list[float]]:
    """Connect and run the sequence; returns the readings taken after each move."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--host", help="simulator address (default: SIMMER_HOST, else 127.0.0.1)")
    parser.add_argument(
        "--port", type=int, help="persistent protocol port (default: SIMMER_PORTS's, else 61202)"
    )
    args = parser.parse_args(argv)

    with connect(args.host, args.port) as robot:
        return drive_sequence(robot)


if __name__ == "__main__":
    try:
        main()
    except ClientError as exc:  # e.g. the simulator is not running
        raise SystemExit(f"error: {exc}") from None
