"""The particle filter example (issue 36): how fast examples/particle_filter.py converges on
the lab maze, and what its filter costs, against the filter as it was (4,000 particles
throughout, the first reading weighed at once: ``localize(adaptive=False)``) over the batched
model (``simmer.batch.Model``) and over the model a team had without it
(``Simulation.expected`` for the readings, a NumPy motion model for the moves, as the old
dead_reckoning_particles.py had): "before".

Each run is the example's ``localize`` with a noisy :class:`~simmer.Simulation` as the robot
(2% error on the four ultrasonic sensors and both drives) from the lab's start, one run per
seed (the robot's and the filter's); the error is the estimate's distance from the true pose
at each reading.

Run ``python benchmarks/bench_particle_filter.py`` (``--plot FILE`` draws the convergence,
``--seeds N``, 16 by default). CPU seconds of the filter's own work (everything but the
simulated robot's), so the load of a shared machine says little.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from simmer import Simulation
from simmer.batch import Model
from simmer.config import load_config
from simmer.config.overrides import with_overrides

HERE = Path(__file__).resolve().parent
ROVER = HERE.parent / "examples" / "lab1_rover.toml"
SENSORS = ["u0", "u1", "u2", "u3"]
NOISE = {f"sensors.u{k}.error": 0.02 for k in range(4)} | {
    "drives.w0.error.y": 0.02,
    "drives.r0.error.rotation": 0.02,
}
MOVES = 12
WITHIN = 2.0
"""Inches: a run counts as localized when its estimate ends this close to the truth."""


def example() -> Any:
    """examples/particle_filter.py as a module."""
    spec = importlib.util.spec_from_file_location(
        "particle_filter", ROVER.parent / "particle_filter.py"
    )
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Timed:
    """A model whose ``move`` and ``expected`` add their CPU seconds to ``moving`` and
    ``weighing``, counting the particles each saw."""

    def __init__(self, model: Any) -> None:
        self.model = model
        self.sensor_ids = model.sensor_ids
        self.cell = model.cell
        self.open_cells = model.open_cells
        self.moving = self.weighing = 0.0
        self.moved = self.weighed = 0

    def move(self, particles: np.ndarray, drive: str, amount: float, rng: Any) -> np.ndarray:
        start = time.process_time()
        out: np.ndarray = self.model.move(particles, drive, amount, rng)
        self.moving += time.process_time() - start
        self.moved += len(particles)
        return out

    def expected(self, particles: np.ndarray) -> np.ndarray:
        start = time.process_time()
        out: np.ndarray = self.model.expected(particles)
        self.weighing += time.process_time() - start
        self.weighed += len(particles)
        return out


class SimulationModel:
    """The model without ``simmer.batch``: ``Simulation.expected`` weighs, and each particle
    moves by the command off by the drive's configured error (relative, one sigma) in NumPy,
    through walls (no collision test)."""

    def __init__(self, config: Any) -> None:
        self.sensor_ids = SENSORS
        self.sim = Simulation(config, seed=0)
        layout = Model(config)  # the maze's cells (what robot.maze() gives a program)
        self.cell = layout.cell
        self.open_cells = layout.open_cells
        self.forward = NOISE["drives.w0.error.y"]
        self.turn = NOISE["drives.r0.error.rotation"]

    def expected(self, particles: np.ndarray) -> np.ndarray:
        return self.sim.expected(particles, self.sensor_ids)

    def move(self, particles: np.ndarray, drive: str, amount: float, rng: Any) -> np.ndarray:
        out = particles.copy()
        n = len(out)
        if drive == "w0":
            step = amount * (1.0 + self.forward * rng.standard_normal(n))
            heading = np.radians(out[:, 2])
            out[:, 0] -= step * np.sin(heading)
            out[:, 1] += step * np.cos(heading)
        else:
            out[:, 2] += amount * (1.0 + self.turn * rng.standard_normal(n))
        return out


def run(
    module: Any, model: Any, config: Any, seed: int, adaptive: bool
) -> tuple[list[float], float, list[int]]:
    """One localization from the lab's start (``seed`` the robot's and the filter's): the
    estimate's error at each reading, the
    filter's own CPU seconds (everything but the simulated robot's) and its particle count at
    each reading."""
    sim = Simulation(config, seed=seed)
    errors: list[float] = []
    counts: list[int] = []
    robot = 0.0

    def read() -> list[float]:
        nonlocal robot
        start = time.process_time()
        out = sim.command(",".join(SENSORS))
        robot += time.process_time() - start
        return out

    def drive(name: str, amount: float) -> None:
        nonlocal robot
        start = time.process_time()
        sim.command(f"{name}-{amount!r}")
        sim.run_until_idle()
        robot += time.process_time() - start

    def report(f: Any) -> None:
        x, y, _ = f.estimate()
        errors.append(math.hypot(x - sim.robot.pose.x, y - sim.robot.pose.y))
        counts.append(len(f.particles))

    start = time.process_time()
    f = module.localize(read, drive, model, MOVES, report, adaptive, seed)
    filtering = time.process_time() - start - robot
    report(f)
    return errors, filtering, counts


RUNS = {
    "example": ("batch", True),
    "as_it_was": ("batch", False),
    "before": ("simulation", False),
}
"""Each measured filter: its model and whether its particle count adapts."""


def measure(seeds: int) -> dict[str, Any]:
    """Each filter over ``seeds`` runs: errors per reading, CPU per localization and per
    model call, particle counts."""
    module = example()
    config = with_overrides(load_config(ROVER), NOISE)
    models = {"batch": Model(config, SENSORS), "simulation": SimulationModel(config)}
    for inner in models.values():
        warm = np.array([[18.0, 18.0, 0.0]])  # compiled code loaded before it is timed
        inner.expected(warm)
        inner.move(warm, "w0", 1.0, np.random.default_rng(0))
    out: dict[str, Any] = {}
    for name, (kind, adaptive) in RUNS.items():
        timed = Timed(models[kind])
        runs = [run(module, timed, config, seed, adaptive) for seed in range(seeds)]
        out[name] = {
            "errors": [r[0] for r in runs],
            "cpu": [r[1] for r in runs],
            "counts": [r[2] for r in runs],
            "move_us": timed.moving / timed.moved * 1e6,
            "weigh_us": timed.weighing / timed.weighed * 1e6,
        }
    return out


def report(figures: dict[str, Any]) -> None:
    """Print each filter's convergence and cost, and the ratios to the one before."""
    labels = {
        "example": "the example (over Model, KLD-sampling, the first reading in stages)",
        "as_it_was": "the example as it was (over Model, 4,000 particles, one weighing)",
        "before": "before (Simulation.expected + NumPy moves, 4,000 particles)",
    }
    before = float(np.median(figures["before"]["cpu"]))
    for name, f in figures.items():
        runs = np.array(f["errors"])
        within = int((runs[:, -1] < WITHIN).sum())
        first = [int(np.argmax(r < WITHIN)) if (r < WITHIN).any() else None for r in runs]
        cpu = np.array(f["cpu"])
        counts = np.array(f["counts"])
        print(
            f"{labels[name]}:\n  {within} of {len(runs)} runs within {WITHIN:g} in after {MOVES}"
            f" moves; first within at reading {first}; final error median"
            f" {np.median(runs[:, -1]):.2f} in, worst {runs[:, -1].max():.2f} in\n"
            f"  CPU for a {MOVES}-move localization: median {np.median(cpu):.3f} s"
            f" ({cpu.min():.3f}-{cpu.max():.3f} s), {np.median(cpu) / before:.2f}x before's;"
            f" per particle: weigh {f['weigh_us']:.2f} us, move one cell {f['move_us']:.2f} us\n"
            f"  particles at each reading (median over runs): "
            f"{[int(c) for c in np.median(counts, axis=0)]}"
        )


def plot(figures: dict[str, Any], path: Path) -> None:
    """Each run's error against the reading, one panel per filter."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    titles = {
        "example": "the example: Model, KLD-sampling, staged first reading",
        "as_it_was": "as it was: Model, 4,000 particles",
        "before": "before: Simulation.expected + NumPy moves",
    }
    fig, axes = plt.subplots(1, len(figures), figsize=(13, 3.8), sharey=True)
    for ax, (name, f) in zip(axes, figures.items(), strict=True):
        for seed, errors in enumerate(f["errors"]):
            ax.plot(range(len(errors)), errors, marker="o", ms=2, lw=1, label=f"seed {seed}")
        ax.axhline(WITHIN, color="grey", ls="--", lw=1)
        ax.set_yscale("log")
        ax.set_xlabel("reading (a move between each)")
        within = int((np.array(f["errors"])[:, -1] < WITHIN).sum())
        ax.set_title(
            f"{titles[name]}\n{within} of {len(f['errors'])} within {WITHIN:g} in;"
            f" CPU {np.median(f['cpu']):.2f} s a localization",
            fontsize=10,
        )
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("estimate's error (in)")
    axes[0].legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> None:
    """Measure, print, and with ``--plot`` draw."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=16)
    parser.add_argument("--plot", type=Path, default=None)
    args = parser.parse_args(argv)
    figures = measure(args.seeds)
    report(figures)
    if args.plot is not None:
        plot(figures, args.plot)


if __name__ == "__main__":
    main()
