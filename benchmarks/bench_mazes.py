"""Maze generator speed and figures (issue 34): a course-sized maze with its ambiguity (goal
< 50 ms), a 100 x 100 maze (goal < 1 s), and the distribution of loops, dead ends and
ambiguity over many seeds (the table in docs/mazes.md).

Run standalone: ``python benchmarks/bench_mazes.py [seeds]``."""

from __future__ import annotations

import sys
import time

import numpy as np

from simmer.config.mazegen import generate
from simmer.config.project import GenerateSettings


def timed(settings: GenerateSettings, repeats: int) -> float:
    """Seconds per maze, the best of ``repeats``."""
    best = float("inf")
    for i in range(repeats):
        start = time.perf_counter()
        generate(settings.model_copy(update={"seed": settings.seed + i}))
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    course = timed(GenerateSettings(), 50)
    big = timed(GenerateSettings(rows=100, cols=100), 3)
    print(f"course-sized maze with its ambiguity: {course * 1000:.1f} ms (goal < 50 ms, "
          f"{50 / (course * 1000):.0f}x under)")  # fmt: skip
    print(f"100 x 100 maze with its ambiguity: {big:.2f} s (goal < 1 s, {1 / big:.1f}x under)")
    figures = [generate(GenerateSettings(seed=s)).figures for s in range(seeds)]
    table = {
        "open cells": [f.open_cells for f in figures],
        "loops per open cell": [f.loop_share for f in figures],
        "dead ends per open cell": [f.dead_end_share for f in figures],
        "ambiguity": [f.ambiguity for f in figures],
    }
    print(f"\ndefault course style over {seeds} seeds:")
    print("| figure | min | 5% | median | 95% | max |\n|---|---|---|---|---|---|")
    for name, values in table.items():
        q = np.percentile(values, [0, 5, 50, 95, 100])
        print(f"| {name} | " + " | ".join(f"{v:.2f}".rstrip("0").rstrip(".") for v in q) + " |")


if __name__ == "__main__":
    main()
