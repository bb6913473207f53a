"""A particle filter that localizes the rover with its LiDAR: each scan is weighed against a
table of the scans the maze would give (a demonstration of SimMeR's LiDAR, not a competition
solution).

The table is the LiDAR's noise-free scans on a 1 in grid, facing heading 0
(``Simulation.lidar_table``, what ``simmer table --sensor l0`` writes): a particle's expected
scan is the table's scan at its LiDAR's position, rotated by its heading, so one table serves
every heading. The robot drives (forward while the way ahead is clear, else a quarter turn),
the particles move with it (with noise), and each new scan reweighs them; the estimate is
reported (``robot.report_pose``) and drawn (``robot.show``).

    cd examples
    simmer run lidar_rover.toml --program "python lidar_localization.py lidar_rover.toml"
"""

from __future__ import annotations

import argparse

import numpy as np

from simmer import Simulation
from simmer.client import Client, connect

PARTICLES = 5000
FIRST = 60_000
"""Particles before the first scan: spread over every open place and heading, enough that
some start within a few inches and degrees of the truth; the first scan leaves PARTICLES."""
BEAMS_USED = 36
"""Beams of each scan weighed (every tenth of 360): enough to tell places apart, and cheap."""
SIGMA = 3.0
"""Inches: the spread of a reading about the table's (the A1M8's noise, the grid's 1 in, the
particles' own error)."""
MISS = 0.2
"""Likelihood of a beam that returned nothing where the table has a return, or the reverse."""
STEP = 6.0
"""Inches a forward move takes."""


class ScanFilter:
    """Particles (x, y, heading) of the robot, weighed by LiDAR scans against a table."""

    def __init__(self, sim: Simulation, maze: dict, lidar: dict, rng: np.random.Generator) -> None:
        self.xs, self.ys, self.table = sim.lidar_table(1.0, lidar["id"])
        self.beams = self.table.shape[2]
        self.mount = np.array(lidar["position"][:2], dtype=float)
        self.rotation = float(lidar["rotation"])
        self.rng = rng
        walls = np.array(maze["walls"])
        self.cell = float(maze["cell_size"])
        cells = np.argwhere(walls != 0)
        pick = cells[rng.integers(len(cells), size=FIRST)]
        self.p = np.column_stack(
            (
                (pick[:, 1] + rng.random(FIRST)) * self.cell,
                (pick[:, 0] + rng.random(FIRST)) * self.cell,
                rng.uniform(0.0, 360.0, FIRST),
            )
        )
        self.w = np.full(FIRST, 1.0 / FIRST)

    def expected(self, used: np.ndarray) -> np.ndarray:
        """Each particle's expected readings of beams ``used``: (particles, beams used)."""
        x, y, h = self.p.T
        rad = np.radians(h)
        px, py = self.mount
        lx = x + px * np.cos(rad) - py * np.sin(rad)
        ly = y + px * np.sin(rad) + py * np.cos(rad)
        j = np.round(lx - self.xs[0]).astype(int)
        i = np.round(ly - self.ys[0]).astype(int)
        outside = (j < 0) | (j >= len(self.xs)) | (i < 0) | (i >= len(self.ys))
        j, i = np.clip(j, 0, len(self.xs) - 1), np.clip(i, 0, len(self.ys) - 1)
        shift = np.round((h + self.rotation) * self.beams / 360.0).astype(int)
        index = (used[None, :] + shift[:, None]) % self.beams
        want = self.table[i[:, None], j[:, None], index]
        want[outside] = np.nan  # off the maze: as unlikely as inside a wall
        return want

    def sense(self, distances: np.ndarray) -> None:
        """Weigh the particles by a scan, then resample."""
        used = np.arange(0, self.beams, self.beams // BEAMS_USED)
        want = self.expected(used)
        got = distances[used][None, :]
        both = (want > 0) & (got > 0)
        error = np.where(both, want - got, 0.0)
        spread = SIGMA + 0.02 * np.where(both, got, 0.0)
        log_l = np.where(both, -0.5 * (error / spread) ** 2, 0.0)
        log_l += np.where(np.isnan(want), -50.0, 0.0)  # inside a solid cell
        log_l += np.where(~both & ((want > 0) != (got > 0)), np.log(MISS), 0.0)
        log_w = np.log(self.w) + np.nan_to_num(log_l, nan=-50.0).sum(axis=1)
        w = np.exp(log_w - log_w.max())
        self.w = w / w.sum()
        positions = (self.rng.random() + np.arange(PARTICLES)) / PARTICLES
        keep = np.minimum(np.searchsorted(np.cumsum(self.w), positions), len(self.w) - 1)
        self.p = self.p[keep] + self.rng.normal(0.0, 1.0, (PARTICLES, 3)) * [0.3, 0.3, 1.5]
        self.w = np.full(PARTICLES, 1.0 / PARTICLES)

    def move(self, forward: float, turn: float) -> None:
        """Motion update: ``forward`` inches along each heading, then ``turn`` degrees, noisy."""
        rad = np.radians(self.p[:, 2])
        ahead = forward + self.rng.normal(0.0, 0.05 * abs(forward) + 0.2, PARTICLES)
        self.p[:, 0] += -np.sin(rad) * ahead
        self.p[:, 1] += np.cos(rad) * ahead
        self.p[:, 2] = (self.p[:, 2] + turn + self.rng.normal(0.0, 2.0, PARTICLES)) % 360.0

    def estimate(self) -> tuple[float, float, float, float]:
        """The mean pose (x, y, heading) and the particles' spread in inches."""
        x, y = self.p[:, 0].mean(), self.p[:, 1].mean()
        rad = np.radians(self.p[:, 2])
        heading = float(np.degrees(np.arctan2(np.sin(rad).mean(), np.cos(rad).mean())) % 360)
        spread = float(np.hypot(self.p[:, 0].std(), self.p[:, 1].std()))
        return float(x), float(y), heading, spread


def localize(robot: Client, sim: Simulation, moves: int, show: bool, seed: int) -> tuple:
    """Drive and filter for at most ``moves`` moves; the final estimate and spread."""
    maze = robot.maze()
    lidar = next(d for d in maze["devices"] if d["kind"] == "lidar")
    f = ScanFilter(sim, maze, lidar, np.random.default_rng(seed))
    low = next(
        (d["id"] for d in maze["devices"] if d["kind"] == "ultrasonic" and d["rotation"] == 0),
        None,
    )

    def sense() -> np.ndarray:
        """Weigh the particles by the first scan made wholly after the last move (the one
        under way then is smeared by it), and report the estimate."""
        first = robot.scan(lidar["id"]).number + 2
        scan = robot.scan(lidar["id"])
        while scan.number < first:
            robot.sleep(0.05)
            scan = robot.scan(lidar["id"])
        f.sense(scan.distances)
        x, y, heading, spread = f.estimate()
        if show:
            robot.show(f.p[::10], pose=(x, y, heading), labels=[(x, y - 8, f"{spread:.1f} in")])
        else:
            robot.report_pose(x, y, heading)
        return scan.distances

    for _ in range(moves):
        distances = sense()
        # the LiDAR sees over the block: the low front sensor, if there is one, sees it
        ahead = distances[0] if distances[0] > 0 else np.inf
        if low is not None:
            ahead = min(ahead, robot.read(low))
        if ahead > STEP + 6:
            robot.drive("w0", STEP)
            robot.wait_idle()
            f.move(STEP, 0.0)
        else:
            robot.drive("r0", 90)
            robot.wait_idle("r0")
            f.move(0.0, 90.0)
    sense()
    return f.estimate()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", help="the configuration the simulator runs")
    parser.add_argument("--moves", type=int, default=12)
    parser.add_argument("--seed", type=int, default=1, help="the filter's own random seed")
    parser.add_argument("--no-show", action="store_true", help="do not draw the particles")
    args = parser.parse_args(argv)
    sim = Simulation.from_config(args.config)
    with connect() as robot:
        x, y, heading, spread = localize(robot, sim, args.moves, not args.no_show, args.seed)
    print(
        f"estimate x {x:.1f} in, y {y:.1f} in, heading {heading:.0f} deg (spread {spread:.1f} in)"
    )


if __name__ == "__main__":
    main()
