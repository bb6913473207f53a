"""Tune obstacle_avoidance.py's two thresholds (its step and its stopping distance) by a search
over 1,024 simulated robots at once, then confirm the choice with an ordinary sweep of the real
program.

    python examples/tune_obstacle_avoidance.py            # the search: a table, before and after
    python examples/tune_obstacle_avoidance.py --confirm  # and then `simmer sweep` of the program

The batch (:class:`simmer.batch.Batch`) runs the program's rule for every robot at once: read
the sensors; stop if the front sensor less a step is under the limit, or any sensor reads under
it; else drive one step forward and wait until it is done. Success is the sweep's: no collision
in 200 steps. The rover is the Lab 1 rover with the noise of sweep_obstacle_avoidance.toml's
hardest row: a forward drive off by up to a half of each move (error 0.25), a drawn curving bias
and 3% sensor error, one seed per robot.
"""

from __future__ import annotations

import argparse
import itertools
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from simmer import load_config, with_overrides
from simmer.batch import Batch

HERE = Path(__file__).resolve().parent
NOISE = {
    "drives.w0.error.y": 0.25,
    "rand_bias": True,
    "bias_strength": [0.02, 0.5],
    **{f"sensors.u{k}.error": 0.03 for k in range(4)},
}
BEFORE = (0.5, 2.0)
"""obstacle_avoidance.py's step (in) and limit (in) as shipped."""
STEPS = (0.25, 0.5, 0.75, 1.0)
LIMITS = (1.5, 2.0, 2.5, 3.0, 3.5)


def success_rate(batch: Batch, step: float, limit: float, max_steps: int = 200) -> float:
    """The share of robots that stop without a collision, each following the program's rule."""
    n = len(batch)
    batch.reset(np.arange(n), batch.seeds.copy())
    batch.step()  # the first reading
    w0 = batch.drive_index("w0")
    speed = 6.0 / 60.0  # the Lab 1 rover's w0: 6 in/s at 60 steps/s
    frames = int(step * 2.5 / speed) + 2  # enough for a step off by 150%
    going = np.ones(n, dtype=bool)
    for _ in range(max_steps):
        r = batch.readings
        going &= ~((r[:, 0] - step < limit) | (r.min(axis=1) < limit))
        if not going.any():
            break
        batch.step(np.where(going, w0, -1), np.full(n, step), frames, going)
    return float((batch.collisions == 0).mean())


def search(robots: int) -> dict[tuple[float, float], float]:
    """The success rate of every (step, limit) pair, over the same ``robots`` seeds."""
    config = with_overrides(load_config(HERE / "lab1_rover.toml"), NOISE)
    batch = Batch(config, list(range(robots)))
    return {
        (step, limit): success_rate(batch, step, limit)
        for step, limit in itertools.product(STEPS, LIMITS)
    }


def confirm(step: float, limit: float, folder: Path, seeds: int) -> int:
    """Run ``simmer sweep`` of the real program with the chosen thresholds and this noise."""
    sweep = folder / "sweep_tuned.toml"
    lines = [
        f'config = "{HERE / "lab1_rover.toml"}"',
        f'program = "python3 -u {HERE / "obstacle_avoidance.py"} --step {step} --limit {limit}"',
        f"seeds = {seeds}",
        "seconds = 120",
        "wall_seconds = 120",
        'success = "collisions == 0"',
        'keep = "nothing"',
        "[grid]",  # one value each: the search's noise
        *(f'"{key}" = [{json.dumps(value)}]' for key, value in NOISE.items()),
    ]
    sweep.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"confirming with: simmer sweep {sweep}")
    return subprocess.call([sys.executable, "-m", "simmer", "sweep", str(sweep)])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", type=int, default=1024, help="seeds per setting")
    parser.add_argument("--confirm", action="store_true", help="then sweep the real program")
    parser.add_argument("--seeds", type=int, default=40, help="runs of the confirming sweep")
    args = parser.parse_args(argv)
    rates = search(args.robots)
    print(f"success rate over {args.robots} seeds (no collision), step x limit:")
    print("step \\ limit " + "".join(f"{limit:>8g}" for limit in LIMITS))
    for step in STEPS:
        print(f"{step:>12g} " + "".join(f"{rates[step, limit]:>8.1%}" for limit in LIMITS))
    # the best rate; among equals, the longest step (fewer moves), then the smallest limit
    best = max(rates, key=lambda k: (rates[k], k[0], -k[1]))
    print(f"before: step {BEFORE[0]:g} in, limit {BEFORE[1]:g} in: {rates[BEFORE]:.1%}")
    print(f"after:  step {best[0]:g} in, limit {best[1]:g} in: {rates[best]:.1%}")
    if args.confirm:
        with tempfile.TemporaryDirectory() as folder:
            return confirm(*best, Path(folder), args.seeds)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
