"""The single robot before and after issue 36's speed-up, measured in turns in one run.

Steps per second of the lab rover with seven sensors (four ultrasonic, a gyroscope, a compass,
an infrared sensor) all sampled every step, as ``bench_core.py``'s first figure, for this
checkout's ``src`` and for an earlier revision's (``--before REV``, default the last commit
before the speed-up), each in its own process. The two processes take turns (one timed run
each per round, best of the rounds), so a change in the machine's load moves both alike.

Run ``python benchmarks/bench_single.py [--before REV] [--rounds N]`` from a git checkout.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
BEFORE = "b8d40b0"
"""The last commit before the single robot's speed-up (issue 36, item 4)."""
STEPS = 6000

CHILD = """
import sys, time
sys.path.insert(0, sys.argv[1])
from bench_core import Stepping, lab_data
import simmer
case = Stepping(lab_data(), "u0,u1,u2,u3,g0,c0,i0")
case(2000)
print(simmer.__file__, flush=True)
for line in sys.stdin:
    count = int(line)
    start = time.process_time()
    case(count)
    print(time.process_time() - start, flush=True)
"""


def source_of(revision: str, into: Path) -> Path:
    """``src`` of ``revision`` extracted under ``into`` (``git archive``)."""
    archive = into / "src.tar"
    with archive.open("wb") as out:
        subprocess.run(["git", "archive", revision, "src"], cwd=ROOT, stdout=out, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(into, filter="data")
    return into / "src"


def start(source: Path) -> subprocess.Popen[str]:
    """A process stepping the lab rover with ``source`` first on its path, warmed up."""
    env = os.environ | {"PYTHONPATH": str(source)}
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(HERE)],
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None
    loaded = child.stdout.readline().strip()
    if not loaded.startswith(str(source)):
        raise SystemExit(f"the process for {source} imported simmer from {loaded}")
    return child


def timed(child: subprocess.Popen[str], count: int) -> float:
    """CPU seconds the child takes for ``count`` steps."""
    assert child.stdin is not None
    assert child.stdout is not None
    child.stdin.write(f"{count}\n")
    child.stdin.flush()
    return float(child.stdout.readline())


def main(before: str = BEFORE, rounds: int = 7) -> dict[str, float]:
    """Measure both in turns; print and return steps per CPU second and their ratio."""
    with tempfile.TemporaryDirectory() as folder:
        children = {
            "before": start(source_of(before, Path(folder))),
            "after": start(ROOT / "src"),
        }
        best = dict.fromkeys(children, float("inf"))
        for _ in range(rounds):
            for name, child in children.items():
                best[name] = min(best[name], timed(child, STEPS))
        for child in children.values():
            assert child.stdin is not None
            child.stdin.close()
            child.wait()
    figures = {name: STEPS / seconds for name, seconds in best.items()}
    figures["ratio"] = figures["after"] / figures["before"]
    print("SimMeR single robot, before and after (lab rover, 7 sensors sampled each step)")
    print(f"  steps per CPU second, {before:<12} {figures['before']:>10,.0f}")
    print(f"  steps per CPU second, this checkout {figures['after']:>10,.0f}")
    print(f"  ratio after / before                {figures['ratio']:>10.2f}   target >= 2")
    return figures


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", default=BEFORE, help="git revision to compare with")
    parser.add_argument("--rounds", type=int, default=7, help="timed runs of each, in turns")
    arguments = parser.parse_args()
    main(arguments.before, arguments.rounds)
