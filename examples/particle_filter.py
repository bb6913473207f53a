"""A particle filter over SimMeR's own motion and sensor model: where in the maze is the robot?

The robot does not know where it starts. 4,000 particles are spread over the open floor; the
robot drives cell by cell (forward when the way ahead is clear, else a quarter turn), and after
each move every particle is moved by the same command under the drive's noise
(:meth:`simmer.batch.Model.move`: the simulator's own drive, bias and walls, for all particles
in one compiled call) and weighed by how well the four ultrasonic readings match what its
sensors would read there (:meth:`simmer.batch.Model.expected`: the simulator's own ray
casting), then resampled to as many particles as the places it still covers need (KLD-sampling:
some 1,000 while three places match, 200 once they agree, so a move costs a twentieth). The
first reading is weighed in stages, the sensors assumed noisier at first, so every place that
matches keeps its particles. The cloud and its mean are drawn over the maze with ``robot.show``
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
"""How many particles are spread over the floor at the start (and the most ever kept)."""
FEWEST = 200
"""The fewest kept once the particles agree."""
BIN = (2.0, 2.0, 15.0)
"""KLD-sampling's bins (in, in, degrees): each distinct place the particles cover counts."""
KLD_ERROR, KLD_Z = 0.05, 2.326
"""KLD-sampling's bound: enough particles that the resampled cloud is within this
Kullback-Leibler distance of the belief with 99% probability (z of the normal's 0.99)."""
SIGMA = 1.5
"""Inches: how far a reading may be from the expected one (the sensors' noise and more)."""
ANNEAL = (8.0, 4.0, 2.0)
"""Inches: the sensors' noise as the first reading's stages assume it, before ``SIGMA``."""
JITTER = (0.3, 0.3, 2.0)
"""Spread added to resampled particles (in, in, degrees), so copies of one particle part."""
DRIVE_SPREAD = 0.03
"""The drive error assumed when the configuration has none (a real robot always has some)."""


def kld_count(k: int) -> int:
    """KLD-sampling's particle count for a belief covering ``k`` bins (Fox 2003)."""
    if k < 2:
        return 1
    a = 2.0 / (9.0 * (k - 1))
    return math.ceil((k - 1) / (2.0 * KLD_ERROR) * (1.0 - a + math.sqrt(a) * KLD_Z) ** 3)


class ParticleFilter:
    """Particles (x, y, heading) with weights, moved and weighed by a :class:`Model`:
    ``count`` spread at the start and the most kept; ``adaptive=False``: all of them
    throughout and the first reading weighed at once (the filter as it was, to compare)."""

    def __init__(
        self, model: Model, count: int = PARTICLES, seed: int = 0, adaptive: bool = True
    ) -> None:
        self.model = model
        self.adaptive = adaptive
        self.most = count
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
        self.first = True

    def move(self, drive: str, amount: float) -> None:
        """The motion update: every particle runs the command, each with its own error."""
        moved = self.model.move(self.particles, drive, amount, self.rng)
        if drive == "w0" and np.allclose(np.std(moved[:, :2] - self.particles[:, :2]), 0.0):
            moved[:, 2] += self.rng.normal(0.0, 1.0, len(moved))  # no error configured
            moved[:, :2] += self.rng.normal(0.0, DRIVE_SPREAD * abs(amount), (len(moved), 2))
        moved[:, 2] %= 360.0
        self.particles = moved

    def sense(self, readings: Sequence[float]) -> None:
        """The measurement update, then resampling when the weights have thinned out. The
        first reading is weighed in stages (progressive correction): as if the sensors were
        8, 4 then 2 in noisy, resampling all of them and spreading them less each time, then
        as they are; the spread particles are too far apart for the sharp weighing alone (it
        leaves one or two, often not where the robot is), while each stage keeps every place
        that nearly matches and lets its particles settle where it matches best."""
        readings = np.asarray(readings, dtype=float)
        if self.adaptive and self.first:
            done = 0.0
            for sigma in ANNEAL:
                share = (SIGMA / sigma) ** 2 - done
                self.weigh(readings, share)
                self.resample(sigma / SIGMA, count=self.most)
                done += share
            self.weigh(readings, 1.0 - done)
            self.resample()  # to as many as the places it found need
        else:
            self.weigh(readings, 1.0)
            if 1.0 / (self.weights**2).sum() < len(self.weights) / 2:
                self.resample()
        self.first = False

    def weigh(self, readings: np.ndarray, share: float) -> None:
        """Multiply the weights by the readings' likelihood raised to ``share``."""
        error = (self.model.expected(self.particles) - readings) / SIGMA
        chi2 = (error**2).sum(axis=1)
        weights = self.weights * np.exp(-0.5 * share * (chi2 - chi2.min()))
        total = weights.sum()
        self.weights = weights / total if total > 0 else np.full(len(weights), 1 / len(weights))

    def resample(self, spread: float = 1.0, count: int | None = None) -> None:
        """Systematic resampling, with a little jitter (``spread`` times ``JITTER``), to
        ``count`` particles or as many as the places the belief covers need (KLD-sampling,
        Fox 2003): thousands while it is spread over the maze, a few hundred once the
        particles agree, so each move and reading costs less."""
        cumulative = np.cumsum(self.weights)
        index = self.draw(cumulative, count or len(self.weights))
        if self.adaptive and count is None:
            bins = np.floor(self.particles[index] / BIN).astype(np.int64)
            bins[:, 2] %= round(360.0 / BIN[2])
            k = len(np.unique(bins, axis=0))
            index = self.draw(cumulative, min(max(kld_count(k), FEWEST), self.most))
        n = len(index)
        jitter = self.rng.normal(0.0, np.multiply(JITTER, spread), (n, 3))
        self.particles = self.particles[index] + jitter
        self.weights = np.full(n, 1.0 / n)

    def draw(self, cumulative: np.ndarray, n: int) -> np.ndarray:
        """``n`` indices drawn by systematic resampling from the weights' running sum."""
        positions = (self.rng.random() + np.arange(n)) / n * cumulative[-1]
        return np.minimum(np.searchsorted(cumulative, positions), len(cumulative) - 1)

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
    adaptive: bool = True,
    seed: int = 0,
) -> ParticleFilter:
    """Drive and filter for ``moves`` moves: ``read()`` gives the model's sensors' readings,
    ``drive(drive, amount)`` moves the robot and returns when it is done. ``adaptive=False``
    is the filter as it was, to compare: 4,000 particles throughout, the first reading weighed
    at once."""
    f = ParticleFilter(model, seed=seed, adaptive=adaptive)
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
            cloud = np.column_stack((f.particles, f.weights))
            robot.show(cloud[:: max(1, len(cloud) // 1000)], pose=f.estimate())

        f = localize(lambda: robot.send(sensors), drive, model, args.moves, report)
        report(f)
    x, y, heading = f.estimate()
    print(f"estimate x {x:.1f} in, y {y:.1f} in, heading {heading:.0f} deg ({f.spread():.1f} in)")


if __name__ == "__main__":
    main()
