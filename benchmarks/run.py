"""Run every SimMeR benchmark and print its figures: ``python benchmarks/run.py``.

Benchmarks measure wall-clock speed on the machine they run on; the unit tests never do.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SUITES = [
    "bench_cli",
    "bench_core",
    "bench_link",
    "bench_link_model",
    "bench_lockstep",
    "bench_soak",
    "bench_window",
    "bench_sweep",
    "bench_localization",
    "bench_limits",
    "bench_lidar",
    "bench_mazes",
    "bench_batch",
    "bench_particle_filter",
    "bench_single",
    "bench_sensors",
    "bench_grade",
    "bench_tap",
]


def main() -> None:
    """Import each benchmark module beside this file and call its ``main()``."""
    for name in SUITES:
        spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
        if spec is None or spec.loader is None:
            raise SystemExit(f"cannot load benchmarks/{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        module.main()
        print()


if __name__ == "__main__":
    main()
