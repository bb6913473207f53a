"""How soon SimMeR's limits act, in wall time: the speed figures the unit tests assert no
longer (a test checks that a limit acts, never how long it took on a shared machine).

- refusing a 10,000 x 10,000 maze, by its size (target: under a second);
- refusing a sweep of 10**12 runs, and a run folder whose events.jsonl is 300 MB, in CPU time
  (target: under a second each; tests/sweep/test_limits.py and
  tests/record/test_hostile_folders.py check only that nothing is expanded or read whole);
- a sweep run's wall-clock limit: the wall time of a run whose program hangs (limit 1.5 s,
  target under 10 s: starting the simulator and the program counts too) and of a policy
  spinning in a thread of its own, as on a Dask worker (limit 0.5 s, target under 5 s).

Run: ``.venv/bin/python benchmarks/bench_limits.py``.
"""

from __future__ import annotations

import copy
import shutil
import sys
import tempfile
import time
import tomllib
from importlib.resources import files
from pathlib import Path

from simmer import Simulation
from simmer.config import config_from_dict
from simmer.errors import ConfigError, ReplayError, SweepError
from simmer.record import RunRecorder
from simmer.sweep import run_sweep
from simmer.sweep.runs import RunSpec, execute
from simmer.sweep.spec import sweep_from_dict
from simmer.view.replay_model import Recording

ROOT = Path(__file__).resolve().parent.parent
LAB1 = ROOT / "examples" / "lab1_rover.toml"
POLICIES = ROOT / "tests" / "fixtures" / "sweep" / "sweep_policies.py"


def refuse_huge_maze() -> float:
    """Wall seconds to refuse a 10,000 x 10,000 maze."""
    text = files("simmer").joinpath("data/default.toml").read_text(encoding="utf-8")
    data = copy.deepcopy(tomllib.loads(text))
    data["walls"] = [[1] * 10_000] * 10_000  # one row, shared: cheap to build
    start = time.perf_counter()
    try:
        config_from_dict(data, "<bench>", ROOT)
    except ConfigError:
        return time.perf_counter() - start
    raise SystemExit("a 10,000 x 10,000 maze was accepted")


def refuse_huge_sweep(folder: Path) -> float:
    """CPU seconds to refuse a sweep of 1000**4 runs."""
    grid = {f"drives.w0.error.{axis}": list(range(1000)) for axis in ("x", "y", "rotation")}
    grid["sensors.u0.error"] = list(range(1000))
    data = {"config": str(LAB1), "program": "python robot.py", "grid": grid}
    start = time.process_time()
    try:
        sweep_from_dict(data, folder)
    except SweepError:
        return time.process_time() - start
    raise SystemExit("a sweep of 10**12 runs was accepted")


def refuse_huge_events(folder: Path) -> float:
    """CPU seconds to refuse a run folder whose events.jsonl is 300 MB (sparse)."""
    run = folder / "huge-events"
    sim = Simulation.from_config()
    with RunRecorder(sim, run):
        sim.step(6)
    with (run / "events.jsonl").open("r+b") as file:
        file.truncate(300 * 2**20)
    start = time.process_time()
    try:
        Recording.load(run)
    except ReplayError:
        return time.process_time() - start
    raise SystemExit("a 300 MB events.jsonl was read")


def hanging_program(folder: Path, limit: float = 1.5) -> float:
    """Wall seconds of a run whose program hangs, stopped at ``limit`` (the slower of two)."""
    command = f'"{sys.executable}" -c "print(chr(0) * 50, flush=True)\nwhile True: pass"'
    spec = sweep_from_dict(
        {"config": str(LAB1), "program": command, "seeds": 2, "wall_seconds": limit}, folder
    )
    run_sweep(spec, folder / "out", workers=2)
    rows = (folder / "out" / "results.csv").read_text(encoding="utf-8").splitlines()
    heading = rows[0].split(",")
    column = heading.index("wall_time")
    return max(float(row.split(",")[column]) for row in rows[1:])


def spinning_policy(folder: Path, limit: float = 0.5) -> float:
    """Wall seconds of a run whose policy spins in a thread, stopped at ``limit``."""
    shutil.copy(POLICIES, folder)
    run = RunSpec(
        str(LAB1), (), 0, "policy", "sweep_policies:spin_forever", str(folder), None, limit
    )
    return execute(run).wall_time


def main() -> dict[str, float]:
    """Measure, print against the targets, return the figures."""
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        figures = {
            "refuse a 10,000 x 10,000 maze (s)": (refuse_huge_maze(), 1.0),
            "refuse a sweep of 10**12 runs (CPU s)": (refuse_huge_sweep(folder), 1.0),
            "refuse a 300 MB events.jsonl (CPU s)": (refuse_huge_events(folder), 1.0),
            "a run whose program hangs, wall limit 1.5 s (s)": (hanging_program(folder), 10.0),
            "a policy spinning in a thread, wall limit 0.5 s (s)": (spinning_policy(folder), 5.0),
        }
    print("SimMeR limits: how soon they act (wall time)")
    for label, (value, target) in figures.items():
        verdict = "meets" if value <= target else "MISSES"
        print(f"  {label:<62} {value:7.3f}  <= {target:g}  {verdict}")
    return {label: value for label, (value, _) in figures.items()}


if __name__ == "__main__":
    main()
