"""Sweep workers without process-wide state (issue 29, item 3): a run leaves its worker's
folder, file descriptors and ``sys.path`` as they were (a program is given its folder and
output when it starts), two folders' policies of one name never mix, a warm simulation is
one run's at a time, the pool's workers are known by the pids they report, and a Dask
cluster whose workers run several threads is refused with one line."""

from __future__ import annotations

import os
import sys
from concurrent.futures import wait
from pathlib import Path

import pytest

from simmer.errors import SweepError
from simmer.sweep import RunSpec, build_config, local_pool, run_sweep, sweep_from_dict
from simmer.sweep.engine import DaskExecutor, _LocalPool
from simmer.sweep.runs import WARM, execute

from helpers import EXAMPLES

pytestmark = pytest.mark.timeout(120)

LAB1 = EXAMPLES / "lab1_rover.toml"
OBSERVER = """\
import os, sys

def observe(robot):
    robot.send("u0")
    seen = [os.getcwd(), os.fstat(1).st_ino, os.fstat(2).st_ino, {folder!r} in sys.path]
    print("the policy saw", seen)
    raise RuntimeError("stop here")
"""


def policy_run(folder: Path, target: str) -> RunSpec:
    return RunSpec(str(LAB1), (), 0, "policy", target, str(folder), wall_seconds=30)


def test_a_policy_run_leaves_the_workers_folder_output_and_path_alone(tmp_path: Path) -> None:
    (tmp_path / "observer.py").write_text(OBSERVER.format(folder=str(tmp_path)))
    here = [os.getcwd(), os.fstat(1).st_ino, os.fstat(2).st_ino, False]
    path = list(sys.path)
    result = execute(policy_run(tmp_path, "observer:observe"))
    assert result.status == "error"
    assert f"the policy saw {here}" in result.detail  # its print is the run's output
    assert "RuntimeError: stop here" in result.detail
    assert sys.path == path
    assert os.getcwd() == here[0]


@pytest.mark.slow
def test_a_program_works_in_the_runs_folder_and_writes_to_the_runs_output(
    tmp_path: Path,
) -> None:
    (tmp_path / "where.py").write_text(
        "import os, sys\nprint('working in', os.getcwd(), file=sys.stderr)\nsys.exit(2)\n"
    )
    before = os.getcwd()
    run = RunSpec(str(LAB1), (), 0, "program", "python where.py", str(tmp_path))
    result = execute(run)
    assert (result.status, result.exit_status) == ("error", 2)
    assert result.detail.endswith(f"working in {tmp_path}")
    assert os.getcwd() == before


def test_policies_of_one_name_in_two_folders_are_each_their_own(tmp_path: Path) -> None:
    """A worker (a Dask worker lives on) runs two sweeps whose policy files share a name:
    the second ran the first one's module, imported under that name."""
    outcomes = {}
    for folder, body in (("a", "robot.send('u0')"), ("b", "raise RuntimeError('from b')")):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "same_name.py").write_text(f"def go(robot):\n    {body}\n")
        outcomes[folder] = execute(policy_run(tmp_path / folder, "same_name:go")).status
    assert outcomes == {"a": "ok", "b": "error"}
    assert "same_name" not in sys.modules  # loaded under a name of its own


def test_a_policy_importing_a_file_beside_it_is_told_why_it_cannot(tmp_path: Path) -> None:
    """A policy is loaded without changing ``sys.path``, so ``import helper`` of a file beside
    it fails: the run's detail says so and what to do, not only ``No module named``."""
    (tmp_path / "helper.py").write_text("STEP = 'u0'\n")
    (tmp_path / "uses_helper.py").write_text(
        "import helper\n\ndef go(robot):\n    robot.send(helper.STEP)\n"
    )
    result = execute(policy_run(tmp_path, "uses_helper:go"))
    assert result.status == "error"
    assert "uses_helper imports 'helper', a file beside it" in result.detail
    assert "its imports must be installed packages" in result.detail


def test_a_warm_simulation_is_one_runs_at_a_time() -> None:
    """Two runs of one configuration at once (threads of one worker) get two simulations;
    one given back is the next run's."""
    run = policy_run(Path("."), "unused:go")
    config = build_config(run.config, run.overrides)
    WARM.clear()
    first = WARM.simulation(run, config)
    second = WARM.simulation(run, config)
    assert first is not second
    WARM.give_back(run, first)
    assert WARM.simulation(run, config) is first
    WARM.clear()


@pytest.mark.slow
def test_a_local_pool_knows_its_workers_by_the_pids_they_report() -> None:
    pool = local_pool(2)()
    assert isinstance(pool, _LocalPool)
    try:
        futures = [pool.submit(os.getpid) for _ in range(8)]
        wait(futures)
        assert {future.result() for future in futures} <= pool.worker_pids()
        assert len(pool.worker_pids()) <= 2
    finally:
        pool.shutdown()


@pytest.mark.slow
def test_a_dask_worker_with_several_threads_is_refused_in_one_line(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    )  # in this process, on Dask's in-process transport
    client = distributed.Client(cluster)
    with pytest.raises(
        SweepError, match=r"runs 2 threads; .* start them with --nthreads 1$"
    ) as refused:
        DaskExecutor(client, cluster)
    assert "\n" not in str(refused.value)
    assert client.status == "closed"
    cluster = distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    )
    spec = sweep_from_dict({"config": str(LAB1), "policy": "none:none", "seeds": 1}, tmp_path)
    engine = lambda: DaskExecutor(distributed.Client(cluster), cluster)  # noqa: E731
    with pytest.raises(SweepError, match="--nthreads 1"):
        run_sweep(spec, tmp_path / "out", engine=engine)
    assert not (tmp_path / "out" / "results.csv").exists()  # nothing to --resume
