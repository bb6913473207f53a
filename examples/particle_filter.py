"""A particle filter over SimMeR's own motion and sensor model: where in the maze is the robot?

The robot does not know where it starts. 4,000 particles are spread over the open floor; the
robot drives cell by cell (forward when the way ahead is clear, else a quarter turn), and after
each move every particle is moved by the same command under the drive's noise
(:meth:`simmer.batch.Model.move`: the simulator's own drive, bias and walls, for all particles
in one compiled call) and weighed by how well the four ultrasonic readings match what its
sensors would read there (:meth:`simmer.batch.Model.expected`: the simulator's own ray
casting), then resampled. The cloud and its mean are drawn over the maze with ``robot.show``
(B in the window hides them), and the mean is reported as the pose estimate
(``robot.report_pose``), so the run's outcome says when it localized. docs/gym.md gives how
fast it converges.

From a folder ``simmer new --localization`` made (in examples/, the rover is lab1_rover.toml)::

    simmer run my_rover.toml --start 1,6,90 --program "python particle_filter.py my_rover.toml"

Pass the configuration the simulator runs, so the model is the same robot's.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Sequence

import numpy as np

from simmer.batch import Model

PARTICLES = 4000
SIGMA = 1.5
"""Inches: how far a reading may be from the expected one (the sensors' noise and more)."""
JITTER = (0.3, 0.3, 2.0)
"""Spread added to resampled particles (in, in, degrees), so copies of one particle part."""
DRIVE_SPREAD = 0.03
"""The drive error assumed when the configuration has none (a real robot always has some)."""


class ParticleFilter:
    """Particles (x, y, heading) with weights, moved and weighed by a :class:`Model`."""

    def __init__(self, model: Model, count: int = PARTICLES, seed: int = 0) -> None:
        self.model = model
        self.rng = np.random.default_rng(seed)
        cell = model.cell
        open_cells = model.open_cells  # (row, column) of every open cell
        pick = open_cells[self.rng.integers(len(open_cells), size=count)]
        self.particles = np.column_stack(
            (
                (pick[:, 1] + self.rng.uniform(0.2, 0.8, count)) * cell,
                (pick[:, 0] + self.rng.uniform(0.2, 0.8, count)) * cell,
                self.rng.uniform(0.0, 360.0, count),
            )
        )
        self.weights = np.full(count, 1.0 / count)

    def move(self, drive: str, amount: float) -> None:
        """The motion update: every particle runs the command, each with its own error."""
        moved = self.model.move(self.particles, drive, amount, self.rng)
        if drive == "w0" and np.allclose(np.std(moved[:, :2] - self.particles[:, :2]), 0.0):
            moved[:, 2] += self.rng.normal(0.0, 1.0, len(moved))  # no error configured
            moved[:, :2] += self.rng.normal(0.0, DRIVE_SPREAD * abs(amount), (len(moved), 2))
        moved[:, 2] %= 360.0
        self.particles = moved

    def sense(self, readings: Sequence[float]) -> None:
        """The measurement update, then resampling when the weights have thinned out."""
        expected = self.model.expected(self.particles)
        error = (expected - np.asarray(readings)) / SIGMA
        likelihood = np.exp(-0.5 * np.minimum((error**2).sum(axis=1), 700.0))
        weights = self.weights * likelihood
        total = weights.sum()
        self.weights = weights / total if total > 0 else np.full(len(weights), 1 / len(weights))
        if 1.0 / (self.weights**2).sum() < len(self.weights) / 2:
            self.resample()

    def resample(self) -> None:
        """Systematic resampling, with a little jitter."""
        n = len(self.weights)
        positions = (self.rng.random() + np.arange(n)) / n
        index = np.minimum(np.searchsorted(np.cumsum(self.weights), positions), n - 1)
        self.particles = self.particles[index] + self.rng.normal(0.0, JITTER, (n, 3))
        self.weights = np.full(n, 1.0 / n)

    def estimate(self) -> tuple[float, float, float]:
        """The weighted mean pose (the heading's mean on the circle)."""
        w = self.weights
        x, y = w @ self.particles[:, 0], w @ self.particles[:, 1]
        rad = np.radians(self.particles[:, 2])
        heading = math.degrees(math.atan2(w @ np.sin(rad), w @ np.cos(rad))) % 360.0
        return float(x), float(y), heading

    def spread(self) -> float:
        """Inches: the weighted standard deviation of the particles' positions."""
        mean = np.array(self.estimate()[:2])
        d2 = ((self.particles[:, :2] - mean) ** 2).sum(axis=1)
        return float(math.sqrt(self.weights @ d2))


def localize(
    read: Callable[[], list[float]],
    drive: Callable[[str, float], None],
    model: Model,
    moves: int,
    report: Callable[[ParticleFilter], None] | None = None,
) -> ParticleFilter:
    """Drive and filter for ``moves`` moves: ``read()`` gives the model's sensors' readings,
    ``drive(drive, amount)`` moves the robot and returns when it is done."""
    f = ParticleFilter(model)
    cell = model.cell
    for _ in range(moves):
        readings = read()
        f.sense(readings)
        if report is not None:
            report(f)
        command = ("w0", cell) if readings[0] > cell else ("r0", 90.0)
        drive(*command)
        f.move(*command)
    f.sense(read())
    return f


def main(argv: list[str] | None = None) -> None:
    from simmer.client import connect

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", help="the configuration the simulator runs")
    parser.add_argument("--moves", type=int, default=12)
    args = parser.parse_args(argv)
    model = Model(args.config, ["u0", "u1", "u2", "u3"])
    with connect() as robot:
        sensors = ",".join(model.sensor_ids)

        def drive(name: str, amount: float) -> None:
            robot.drive(name, amount)
            robot.wait_idle(name)

        def report(f: ParticleFilter) -> None:
            robot.show(np.column_stack((f.particles, f.weights))[::4], pose=f.estimate())

        f = localize(lambda: robot.send(sensors), drive, model, args.moves, report)
        report(f)
    x, y, heading = f.estimate()
    print(f"estimate x {x:.1f} in, y {y:.1f} in, heading {heading:.0f} deg ({f.spread():.1f} in)")


if __name__ == "__main__":
    main()
