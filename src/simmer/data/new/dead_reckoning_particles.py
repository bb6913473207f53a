"""Dead reckoning with a particle cloud: where may the robot be after each move of the lab's
sequence, if each move is off by a little? (a motion model alone, no sensing: watch the cloud
grow; examples/histogram_localization.py then narrows a belief down with the sensors).

    simmer run --program "python examples/dead_reckoning_particles.py"

The cloud (2,000 particles), its mean with a 2-sigma ellipse and the planned path are drawn over
the maze with ``robot.show`` (B in the window hides them), and the mean is the pose estimate.
"""

from __future__ import annotations

import math

import numpy as np

from simmer.client import connect

SEQUENCE = [("w0", 36), ("r0", 90), ("w0", 36), ("r0", 90), ("w0", 12), ("r0", -90), ("w0", 24)]
PARTICLES = 2000
DRIVE_NOISE = 0.05
"""Relative error of a drive (one sigma)."""
TURN_NOISE = 3.0
"""Degrees of error of a turn (one sigma)."""


def move(cloud: np.ndarray, drive: str, amount: float, rng: np.random.Generator) -> None:
    """Move every particle as commanded, each with its own error."""
    n = len(cloud)
    if drive == "w0":
        step = amount * (1 + DRIVE_NOISE * rng.standard_normal(n))
        heading = np.radians(cloud[:, 2] + rng.normal(0, 1.0, n))
        cloud[:, 0] -= step * np.sin(heading)
        cloud[:, 1] += step * np.cos(heading)
    else:
        cloud[:, 2] += amount + TURN_NOISE * rng.standard_normal(n)


def main() -> None:
    rng = np.random.default_rng(0)
    with connect() as robot:
        start = robot.maze()["start"]["pose"] or [6.0, 42.0, 180.0]
        cloud = np.tile([*start, 1.0], (PARTICLES, 1))
        path, heading = [start[:2]], start[2]  # the planned path: the moves without error
        for drive, amount in SEQUENCE:
            if drive == "r0":
                heading += amount
            else:
                x, y = path[-1]
                h = math.radians(heading)
                path.append([x - amount * math.sin(h), y + amount * math.cos(h)])
        for drive, amount in SEQUENCE:
            robot.drive(drive, amount)
            robot.wait_idle(drive)
            move(cloud, drive, amount, rng)
            mean = cloud[:, :3].mean(axis=0)
            robot.show(
                cloud,
                pose=tuple(mean),
                cov=np.cov(cloud[:, :2].T).tolist(),
                path=path,
                labels=[(mean[0], mean[1] - 4, f"after {drive} {amount:g}")],
            )
        robot.sleep(1.0)  # the last belief stays on screen (and in a video) for a second


if __name__ == "__main__":
    main()
