"""Lab Task 1: advance in small steps; stop before a step would take the front ultrasonic
sensor within 2 in of an obstacle, or as soon as any sensor reads under 2 in.

Start the simulator first (``simmer run``), then, in a second terminal with SimMeR's
environment active (the README's Quick start says how), run
``python obstacle_avoidance.py`` in the folder ``simmer new`` made (in SimMeR's own folder:
``python examples/obstacle_avoidance.py``).
Without noise it stops 2 to 2.5 in from the wall ahead (the lab rover's nose is 1.5 in ahead
of its front sensor). Try it with the lab rover's noise lines uncommented (``simmer run
my_rover.toml``): small steps and a look before each one keep it off the walls even when the
drives drift, but not always: ``simmer sweep sweep_obstacle_avoidance.toml`` finds when not.
"""

from __future__ import annotations

import argparse

from simmer.client import connect
from simmer.errors import ClientError

SENSORS = "u0,u1,u2,u3"
LIMIT = 2.0  # in


def main(argv: list[str] | None = None) -> int:
    """Advance until blocked; returns how many steps were taken."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--host", help="simulator address (default: SIMMER_HOST, else 127.0.0.1)")
    parser.add_argument(
        "--port", type=int, help="persistent protocol port (default: SIMMER_PORTS's, else 61202)"
    )
    parser.add_argument("--step", type=float, default=0.5, help="inches per step")
    parser.add_argument("--limit", type=float, default=LIMIT, help="inches kept from obstacles")
    parser.add_argument("--max-steps", type=int, default=200)
    args = parser.parse_args(argv)

    with connect(args.host, args.port) as robot:
        for step in range(args.max_steps):
            readings = robot.send(SENSORS)
            print(f"step {step:3d}  " + "  ".join(f"u{i} {v:6.2f}" for i, v in enumerate(readings)))
            ahead = readings[0]  # u0 faces forward: the one sensor a step takes closer
            if ahead - args.step < args.limit or min(readings) < args.limit:
                print(f"obstacle {min(readings):.2f} in away: stopping")
                return step
            robot.drive("w0", args.step)
            robot.wait_idle()
    print("no obstacle within the step limit")
    return args.max_steps


if __name__ == "__main__":
    try:
        main()
    except ClientError as exc:  # e.g. the simulator is not running
        raise SystemExit(f"error: {exc}") from None
