"""A textbook histogram filter: where in the maze is the robot? (a demonstration of SimMeR's
localization tools, not a competition solution).

The belief is a probability for every open cell and each of four headings. The robot drives
cell by cell (forward when the way ahead is clear, else it turns left), and after each move
the belief is shifted by the move (the motion update) and weighed by how well the four
ultrasonic readings match the readings expected in each state (the measurement update). The
maze comes from ``robot.maze()``, the expected readings from ``Simulation.expected`` (the
simulator's own geometry, noise free), and the belief is drawn over the maze with
``robot.show`` (press B in the window to hide it); ``robot.report_pose`` lets the run's
outcome say when it localized.

    simmer run --program "python examples/histogram_localization.py"

Pass the configuration the simulator runs (``python examples/histogram_localization.py
my_rover.toml``) so the expected readings are the same robot's; ``--no-show`` runs the
same filter without drawing it.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from simmer import Simulation, with_overrides
from simmer.client import Client, connect

HEADINGS = (0.0, 90.0, 180.0, 270.0)
"""Degrees from +y: facing +y, -x, -y, +x."""
STEP = {0: (1, 0), 1: (0, -1), 2: (-1, 0), 3: (0, 1)}
"""(row, column) a move forward changes, by heading index."""
SIGMA = 2.0
"""Inches: how far a reading may be from the expected one (the sensors' noise and more)."""
MOVE_SUCCESS = 0.9
"""Chance a move forward gets to the next cell (else the robot is taken to have stayed)."""


class HistogramFilter:
    """P(row, column, heading) over the open cells of the maze."""

    def __init__(self, maze: dict[str, object], sim: Simulation, sensors: list[str]) -> None:
        walls = np.array(maze["walls"])
        self.cell = float(maze["cell_size"])  # type: ignore[arg-type]
        self.open = walls != 0
        rows, cols = walls.shape
        self.belief = np.zeros((rows, cols, 4))
        self.belief[self.open] = 1.0
        self.belief /= self.belief.sum()
        r, c, h = np.meshgrid(np.arange(rows), np.arange(cols), np.arange(4), indexing="ij")
        poses = np.column_stack(
            (
                (c.ravel() + 0.5) * self.cell,
                (r.ravel() + 0.5) * self.cell,
                np.take(HEADINGS, h.ravel()),
            )
        )
        # the readings each state would give, from the walls alone
        self.expected = sim.expected(poses, sensors, block=False).reshape(rows, cols, 4, -1)

    def sense(self, readings: list[float]) -> None:
        """Measurement update: weigh each state by the likelihood of the readings."""
        error = self.expected - np.array(readings)
        likelihood = np.exp(-0.5 * (error / SIGMA) ** 2).prod(axis=-1)
        self.belief *= likelihood * self.open[..., None]
        total = self.belief.sum()
        if total > 0:
            self.belief /= total
        else:  # nothing fits: start again from not knowing
            self.belief = np.repeat(self.open[..., None], 4, axis=2) / (4.0 * self.open.sum())

    def forward(self) -> None:
        """Motion update for one cell forward."""
        moved = self.belief * (1 - MOVE_SUCCESS)
        rows, cols = self.open.shape
        for h, (dr, dc) in STEP.items():
            source = self.belief[
                max(0, -dr) : rows - max(0, dr), max(0, -dc) : cols - max(0, dc), h
            ]
            moved[max(0, dr) : rows + min(0, dr), max(0, dc) : cols + min(0, dc), h] += (
                source * MOVE_SUCCESS
            )
        moved *= self.open[..., None]
        self.belief = moved / moved.sum()

    def turn_left(self) -> None:
        """Motion update for a quarter turn anticlockwise: heading index + 1."""
        self.belief = np.roll(self.belief, 1, axis=2)

    def best(self) -> tuple[float, float, float, float]:
        """The most likely state as (x, y, heading) and its probability."""
        r, c, h = np.unravel_index(int(self.belief.argmax()), self.belief.shape)
        x, y = (c + 0.5) * self.cell, (r + 0.5) * self.cell
        return x, y, HEADINGS[h], float(self.belief[r, c, h])

    def show(self, robot: Client) -> None:
        """Draw the belief: cells (summed over headings), each state as a particle, the best."""
        r, c, h = np.nonzero(self.belief > 1e-4)
        particles = np.column_stack(
            (
                (c + 0.5) * self.cell,
                (r + 0.5) * self.cell,
                np.take(HEADINGS, h),
                self.belief[r, c, h],
            )
        )
        x, y, heading, p = self.best()
        robot.show(
            particles,
            cells=self.belief.sum(axis=2),
            pose=(x, y, heading),
            ellipse=(self.cell / 2, self.cell / 2, 0.0),
            labels=[(x, y + 0.6 * self.cell, f"p = {p:.2f}")],
        )


def localize(
    robot: Client,
    sim: Simulation,
    moves: int,
    sensors: list[str] | None = None,
    show: bool = True,
) -> tuple[float, ...]:
    """Drive and filter for ``moves`` moves with ``sensors`` (default: every ultrasonic one;
    the first must face forward), sensing before each move and after the last; the final best
    guess (x, y, heading, p), made where the robot ends."""
    maze = robot.maze()
    if maze.get("maze") != _named_maze(sim):  # the simulator runs another maze (a sweep's)
        sim = Simulation(with_overrides(sim.config, {"maze": maze["maze"]}))
    if not sensors:
        sensors = [d["id"] for d in maze["devices"] if d["kind"] == "ultrasonic"]
    front = sensors[0]
    f = HistogramFilter(maze, sim, sensors)
    for move in range(moves + 1):
        readings = robot.send(",".join(sensors))
        f.sense(readings)
        if show:
            f.show(robot)  # its pose counts as the estimate
        else:
            robot.report_pose(*f.best()[:3])
        if move == moves:  # the last estimate is made after the last move, where it ends
            break
        if readings[sensors.index(front)] > f.cell:
            robot.drive("w0", f.cell)
            robot.wait_idle()
            f.forward()
        else:
            robot.drive("r0", 90)
            robot.wait_idle("r0")
            f.turn_left()
    return f.best()


def _named_maze(sim: Simulation) -> object:
    """The maze ``sim``'s configuration names, as ``robot.maze()`` reports it."""
    named = sim.config.settings.maze
    return named if named is None or isinstance(named, str) else named.model_dump(mode="json")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", help="the configuration the simulator runs")
    parser.add_argument("--moves", type=int, default=14)
    parser.add_argument(
        "--sensors",
        default="",
        help="ultrasonic sensors to use, the forward one first (default: all): with only u0 "
        "the belief takes a few moves to converge; with all four it knows at once in the lab maze",
    )
    parser.add_argument("--no-show", action="store_true", help="do not draw the belief")
    args = parser.parse_args(argv)
    sim = Simulation.from_config(args.config)
    with connect() as robot:
        sensors = [s for s in args.sensors.split(",") if s]
        x, y, heading, p = localize(robot, sim, args.moves, sensors, show=not args.no_show)
    print(f"best guess x {x:.1f} in, y {y:.1f} in, heading {heading:g} deg (p = {p:.2f})")
    if not math.isfinite(p):
        raise SystemExit(1)


if __name__ == "__main__":
    main()
