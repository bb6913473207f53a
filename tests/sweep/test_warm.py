"""Warm workers (issue 12): a worker keeps one simulation per configuration and overrides and
resets it to each run's seed; a run on a reset simulation is the run on a fresh one, row for
row, in any order of seeds."""

from __future__ import annotations

import re
import shutil
import sys
from pathlib import Path

import pytest

from simmer.sweep import RunResult, RunSpec, build_config
from simmer.sweep.results import row
from simmer.sweep.runs import WARM, execute
from simmer.world import Simulation

from helpers import (
    EXAMPLES,
    LAB_SEQUENCE,
    REPO,
    make_config,
    noisy_config,
    noisy_data,
    run_sequence,
)

pytestmark = pytest.mark.timeout(300)

LAB1 = EXAMPLES / "lab1_rover.toml"
FIXTURES = REPO / "tests" / "fixtures" / "sweep"
SEEDS = [0, 1, 2]
NOISE = (("drives.w0.error.y", 0.05), ("drives.r0.error.rotation", 0.02), ("sensors.*.error", 0.05))


@pytest.mark.slow
def test_reset_with_a_seed_starts_as_a_new_simulation_with_that_seed() -> None:
    config = noisy_config()

    def readings(sim: Simulation) -> list[object]:
        run_sequence(sim, LAB_SEQUENCE[:4])
        return [sim.robot.pose, sim.command("u0,u1,u2,u3"), sim.time, sim.steps]

    fresh = {seed: readings(Simulation(config, seed=seed)) for seed in SEEDS}
    assert len({str(values) for values in fresh.values()}) == len(SEEDS)  # the seed matters
    warm = Simulation(config, seed=99)
    readings(warm)
    for seed in [*SEEDS, *reversed(SEEDS)]:
        warm.reset(seed=seed)
        assert warm.seed == seed
        assert readings(warm) == fresh[seed], seed
    warm.reset()  # without a seed: the same seed again
    assert warm.seed == SEEDS[0]
    assert readings(warm) == fresh[SEEDS[0]]


def test_a_reset_says_the_lenient_command_warning_again(caplog: pytest.LogCaptureFixture) -> None:
    """A run on a reset simulation logs what a run on a new one logs (its output is kept)."""
    data = noisy_data()
    data["lenient_commands"] = True
    sim = Simulation(make_config(data), seed=1)
    for seed in (1, 2):
        caplog.clear()
        sim.command("u0xyz")  # lenient: 'xyz' is read as 0
        sim.command("u0xyz")
        assert [r.message for r in caplog.records].count(caplog.records[0].message) == 1
        assert "as in the original SimMeR" in caplog.records[0].message
        sim.reset(seed=seed)


def comparable(run: RunSpec, result: RunResult) -> tuple[list[str], dict[str, bytes]]:
    """The run's results row without its wall time, and the kept files a run always writes
    the same (the manifest and report hold the start time and wall seconds; the events name a
    program's connection by its port, which the system chooses)."""
    cells = row(run, result, "runs/x")
    del cells[-4]  # wall_time: see results.TAIL_COLUMNS
    same = ("events.jsonl", "trace.csv", "first.png", "last.png")
    files = {name: data for name, data in result.files.items() if name in same}
    files["events.jsonl"] = re.sub(rb"127\.0\.0\.1:\d+", b"PORT", files["events.jsonl"])
    return cells, files


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["policy", "program"])
def test_a_warm_run_is_the_fresh_run_for_every_seed_in_either_order(
    tmp_path: Path, kind: str
) -> None:
    shutil.copy(FIXTURES / "sweep_policies.py", tmp_path)
    shutil.copy(FIXTURES / "short_drive.py", tmp_path)
    controller = (
        "sweep_policies:lab_sequence" if kind == "policy" else f'"{sys.executable}" short_drive.py'
    )
    runs = {
        seed: RunSpec(
            str(LAB1),
            NOISE,
            seed,
            kind,
            controller,
            str(tmp_path),
            wall_seconds=30,
            success="reached",  # every run fails: its folder and frames come back
            keep="failures",
        )
        for seed in SEEDS
    }
    build_config(str(LAB1), NOISE)
    fresh = {}
    for seed in SEEDS:
        WARM.clear()
        fresh[seed] = comparable(runs[seed], execute(runs[seed]))
    assert fresh[0][0][-5:-3] == ["ok", "0" if kind == "program" else ""]
    assert set(fresh[0][1]) == {"events.jsonl", "trace.csv", "first.png", "last.png"}
    assert len({str(cells) for cells, _ in fresh.values()}) == len(SEEDS)
    for order in (SEEDS, list(reversed(SEEDS))):
        WARM.clear()
        built = WARM.built
        for seed in order:
            assert comparable(runs[seed], execute(runs[seed])) == fresh[seed], (order, seed)
        assert WARM.built == built + 1  # one simulation, reset for each later run
    WARM.clear()
