"""Calibration ground truth: does ``simmer calibrate`` recover a robot's hidden settings?

Each trial is a "robot" that is a simulator with hidden bias and error settings (drawn per
trial: :func:`simmer.calibrate.groundtruth.hidden_settings`) serving its serial port in real
time; the calibration routine runs on it through ``simmer tap``; the fit's 99% interval of
each setting either holds the hidden value or not; and ``simmer compare`` with the fitted
configuration counts the run's readings inside its 99% band, each seed drawing the fitted
settings from their intervals (and, for comparison, with the fitted values alone). Prints, per
setting, in how many trials its interval held the truth (the issue asks 90% or more), and the
share of readings inside the band per trial (95% or more). Each trial takes about a minute of
wall time, mostly the robot driving in real time; ``--jobs`` runs trials side by side.

Run standalone: ``.venv/bin/python benchmarks/calibration_recovery.py [--trials 20] [--jobs 2]
[--json results.json]``. Not in ``benchmarks/run.py``: it measures correctness, not speed.
"""

from __future__ import annotations

import argparse
import json
import logging
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any


def one(number: int, folder: str, seeds: int) -> dict[str, Any]:
    """One trial, as data."""
    logging.basicConfig(level=logging.ERROR)
    from simmer.calibrate.groundtruth import trial
    from simmer.config import load_config

    found = trial(number, Path(folder) / f"trial{number}", load_config(), seeds=seeds, point=True)
    return found.as_dict()


def main(trials: int = 20, jobs: int = 2, seeds: int = 100, out: str | None = None) -> None:
    """Run the trials and print what they recovered."""
    with tempfile.TemporaryDirectory() as folder, ProcessPoolExecutor(jobs) as pool:
        futures = [pool.submit(one, n, folder, seeds) for n in range(1, trials + 1)]
        results = [f.result() for f in futures]
    keys = list(results[0]["settings"])
    print(f"calibration ground truth: {trials} trials, compare over {seeds} seeds")
    print(f"  {'setting':28s} interval held the hidden value")
    for key in keys:
        held = sum(r["settings"][key]["covered"] for r in results)
        print(f"  {key:28s} {held:2d} of {trials} ({held / trials:.0%})")
    for name, what in (
        ("inside", "drawn from the fit's intervals"),
        ("inside_point", "fitted values alone"),
    ):
        inside = [r[name] for r in results]
        print(
            f"  readings inside the fitted band ({what}): lowest {min(inside):.1%}, median "
            f"{sorted(inside)[len(inside) // 2]:.1%}; trials at 95% or more: "
            f"{sum(v >= 0.95 for v in inside)} of {trials}"
        )
    print(
        "  per trial (intervals, point values): "
        + ", ".join(f"{r['trial']}: {r['inside']:.1%} {r['inside_point']:.1%}" for r in results)
    )
    if out:
        Path(out).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    main(args.trials, args.jobs, args.seeds, args.json)
