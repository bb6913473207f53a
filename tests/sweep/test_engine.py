"""Engines (issue 12): the same sweep gives the same table, row for row (wall times aside), on
the local process pool with one or two workers and on a Dask cluster of real worker processes;
for a Python policy and for an external program talking TCP."""

from __future__ import annotations

import csv
import shutil
import sys
from pathlib import Path
from typing import Any

import pytest

from simmer.sweep import dask_engine, run_sweep, sweep_from_dict

from helpers import EXAMPLES, REPO, wait_for

distributed = pytest.importorskip("distributed")
psutil = pytest.importorskip("psutil")  # installed with distributed

pytestmark = pytest.mark.timeout(300)

LAB1 = EXAMPLES / "lab1_rover.toml"
FIXTURES = REPO / "tests" / "fixtures" / "sweep"
NOISE = "drives.w0.error.y"


def children() -> list[Any]:
    """This process's living child processes (a zombie has ended), but multiprocessing's
    resource tracker and fork server (each started with the first pool that needs it, they
    stay until this process ends)."""
    kept = []
    for child in psutil.Process().children(recursive=True):
        try:
            command = " ".join(child.cmdline())
        except (psutil.ZombieProcess, psutil.NoSuchProcess):
            continue  # it has ended (a zombie waits only for its parent to collect it)
        if not any(name in command for name in ("resource_tracker", "forkserver")):
            kept.append(child)
    return kept


@pytest.fixture(scope="module")
def cluster() -> Any:
    """A local Dask cluster of two worker processes with one thread each, for the module."""
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",
    ) as running:
        yield running
    wait_for(lambda: not children(), "the closed cluster's workers to exit", 60)


def table(folder: Path) -> list[dict[str, str]]:
    """results.csv without the wall times."""
    with (folder / "results.csv").open(encoding="utf-8", newline="") as file:
        return [{k: v for k, v in r.items() if k != "wall_time"} for r in csv.DictReader(file)]


def kept_files(folder: Path) -> dict[str, bytes]:
    """The kept runs' frames and traces, by path (the same bytes from any engine)."""
    return {
        str(path.relative_to(folder)): path.read_bytes()
        for pattern in ("runs/*/*.png", "runs/*/trace.csv")
        for path in sorted(folder.glob(pattern))
    }


@pytest.mark.slow
def test_a_policy_sweep_is_the_same_on_every_engine(tmp_path: Path, cluster: Any) -> None:
    shutil.copy(FIXTURES / "sweep_policies.py", tmp_path)
    data = {
        "config": str(LAB1),
        "policy": "sweep_policies:lab_sequence",
        "seeds": 2,
        "grid": {NOISE: [0.0, 0.05]},
        "sample": {"count": 2, "sensors.*.error": {"uniform": [0.0, 0.05]}},
    }
    spec = sweep_from_dict(data, tmp_path)
    run_sweep(spec, tmp_path / "one", workers=1)
    run_sweep(spec, tmp_path / "two", workers=2)
    run_sweep(spec, tmp_path / "dask", engine=dask_engine(cluster.scheduler_address))
    one = table(tmp_path / "one")
    assert len(one) == 8
    assert {r["success"] for r in one} == {"True", "False"}
    assert len({r["final_x"] for r in one}) > 2  # noise: the seeds differ
    assert table(tmp_path / "two") == one
    assert table(tmp_path / "dask") == one
    frames = kept_files(tmp_path / "one")
    assert any(name.endswith("last.png") for name in frames)
    assert kept_files(tmp_path / "two") == frames
    assert kept_files(tmp_path / "dask") == frames


@pytest.mark.slow
def test_a_program_sweep_is_the_same_on_every_engine(tmp_path: Path) -> None:
    """The external program talks TCP to a simulator served on free ports in each worker; the
    Dask engine here starts (and stops) a local cluster of its own."""
    shutil.copy(FIXTURES / "short_drive.py", tmp_path)
    data = {
        "config": str(LAB1),
        "program": f'"{sys.executable}" short_drive.py',
        "seeds": 2,
        "grid": {NOISE: [0.0, 0.1]},
        "success": "path_length > 15.9",
    }
    spec = sweep_from_dict(data, tmp_path)
    run_sweep(spec, tmp_path / "one", workers=1)
    run_sweep(spec, tmp_path / "two", workers=2)
    before = children()
    run_sweep(spec, tmp_path / "dask", engine=dask_engine(workers=2))
    assert children() == before  # its cluster and the cluster's workers are gone
    one = table(tmp_path / "one")
    assert [(r[NOISE], r["seed"], r["status"]) for r in one] == [
        ("0.0", "0", "ok"), ("0.0", "1", "ok"), ("0.1", "0", "ok"), ("0.1", "1", "ok"),
    ]  # fmt: skip
    assert len({r["final_y"] for r in one}) == 3  # no noise: one place; noise: one per seed
    assert table(tmp_path / "two") == one
    assert table(tmp_path / "dask") == one
