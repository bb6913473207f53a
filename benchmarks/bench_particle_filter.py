"""The particle filter example (issue 36): how fast examples/particle_filter.py converges on
the lab maze, and what its filter costs, over the batched model (``simmer.batch.Model``)
against the same filter over the model a team had without it (``Simulation.expected`` for the
readings, a NumPy motion model for the moves, as the old dead_reckoning_particles.py had).

Each run is the example's ``localize`` with a noisy :class:`~simmer.Simulation` as the robot
(2% error on the four ultrasonic sensors and both drives) from the lab's start, one run per
seed; the error is the estimate's distance from the true pose at each reading.

Run ``python benchmarks/bench_particle_filter.py`` (``--plot FILE`` draws the convergence,
``--seeds N``). CPU seconds of the filter's own work (its moves and weighing), so the load of
a shared machine says little.
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
    ``weighing``, counting each."""

    def __init__(self, model: Any) -> None:
        self.model = model
        self.sensor_ids = model.sensor_ids
        self.cell = model.cell
        self.open_cells = model.open_cells
        self.moving = self.weighing = 0.0
        self.moves = self.weighs = 0

    def move(self, particles: np.ndarray, drive: str, amount: float, rng: Any) -> np.ndarray:
        start = time.process_time()
        out: np.ndarray = self.model.move(particles, drive, amount, rng)
        self.moving += time.process_time() - start
        self.moves += 1
        return out

    def expected(self, particles: np.ndarray) -> np.ndarray:
        start = time.process_time()
        out: np.ndarray = self.model.expected(particles)
        self.weighing += time.process_time() - start
        self.weighs += 1
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


def run(module: Any, model: Any, config: Any, seed: int) -> list[float]:
    """One localization from the lab's start: the estimate's error at each reading."""
    sim = Simulation(config, seed=seed)
    errors: list[float] = []

    def read() -> list[float]:
        return sim.command(",".join(SENSORS))

    def drive(name: str, amount: float) -> None:
        sim.command(f"{name}-{amount!r}")
        sim.run_until_idle()

    def report(f: Any) -> None:
        x, y, _ = f.estimate()
        errors.append(math.hypot(x - sim.robot.pose.x, y - sim.robot.pose.y))

    f = module.localize(read, drive, model, MOVES, report)
    report(f)
    return errors


def measure(seeds: int) -> dict[str, Any]:
    """Both models over ``seeds`` runs: errors per reading, CPU per filter update."""
    module = example()
    config = with_overrides(load_config(ROVER), NOISE)
    out: dict[str, Any] = {}
    for name, inner in (("batch", Model(config, SENSORS)), ("simulation", SimulationModel(config))):
        warm = np.array([[18.0, 18.0, 0.0]])  # compiled code loaded before it is timed
        inner.expected(warm)
        inner.move(warm, "w0", 1.0, np.random.default_rng(0))
        timed = Timed(inner)
        runs = [run(module, timed, config, seed) for seed in range(seeds)]
        out[name] = {
            "errors": runs,
            "move_ms": timed.moving / timed.moves * 1000,
            "weigh_ms": timed.weighing / timed.weighs * 1000,
        }
    return out


def report(figures: dict[str, Any]) -> None:
    """Print each model's convergence and cost, and the ratio."""
    for name, f in figures.items():
        runs = np.array(f["errors"])
        within = int((runs[:, -1] < WITHIN).sum())
        first = [int(np.argmax(r < WITHIN)) if (r < WITHIN).any() else None for r in runs]
        print(
            f"{name:>10}: {within} of {len(runs)} runs within {WITHIN:g} in after {MOVES} moves;"
            f" first within at reading {first}; final error median {np.median(runs[:, -1]):.2f} in;"
            f" CPU per update of 4,000 particles: weigh {f['weigh_ms']:.1f} ms,"
            f" move {f['move_ms']:.1f} ms"
        )
    batch, before = figures["batch"], figures["simulation"]
    mine = batch["weigh_ms"] + batch["move_ms"]
    theirs = before["weigh_ms"] + before["move_ms"]
    print(
        f"  weighing: the batched model {before['weigh_ms'] / batch['weigh_ms']:.1f}x cheaper;"
        f" moving (the robot's steps, walls tested): {batch['move_ms'] / before['move_ms']:.0f}x"
        f" dearer; a whole update {mine:.1f} ms against {theirs:.1f} ms ({mine / theirs:.1f}x),"
        f" a {MOVES}-move localization {mine * MOVES / 1000:.2f} s against"
        f" {theirs * MOVES / 1000:.2f} s of CPU"
    )


def plot(figures: dict[str, Any], path: Path) -> None:
    """Each run's error against the reading, one panel per model."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    titles = {
        "batch": "simmer.batch.Model (the example)",
        "simulation": "Simulation.expected + NumPy moves (before)",
    }
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, (name, f) in zip(axes, figures.items(), strict=True):
        for seed, errors in enumerate(f["errors"]):
            ax.plot(range(len(errors)), errors, marker="o", ms=3, label=f"seed {seed}")
        ax.axhline(WITHIN, color="grey", ls="--", lw=1)
        ax.set_yscale("log")
        ax.set_xlabel("reading (a move between each)")
        ax.set_title(
            f"{titles[name]}\nCPU per update: weigh {f['weigh_ms']:.0f} ms, "
            f"move {f['move_ms']:.0f} ms",
            fontsize=10,
        )
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("estimate's error (in)")
    axes[0].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> None:
    """Measure, print, and with ``--plot`` draw."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--plot", type=Path, default=None)
    args = parser.parse_args(argv)
    figures = measure(args.seeds)
    report(figures)
    if args.plot is not None:
        plot(figures, args.plot)


if __name__ == "__main__":
    main()
