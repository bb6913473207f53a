"""Sweeps: run one controller over many seeds and configuration settings, in parallel, and
show how often it succeeds (``simmer sweep SWEEP.toml``).

:func:`load_sweep` reads a sweep file (:mod:`simmer.sweep.spec`), :func:`run_sweep` runs it on
a process pool or a Dask cluster (:mod:`simmer.sweep.engine`), each run described by a
picklable :class:`RunSpec` and carried out by :func:`execute` (:mod:`simmer.sweep.runs`), and
writes ``results.csv`` and ``summary.md`` (:mod:`simmer.sweep.results`).
"""

from simmer.sweep.engine import SweepResult, dask_engine, local_pool, run_sweep
from simmer.sweep.results import wilson_interval
from simmer.sweep.runs import RunResult, RunSpec, apply_overrides, build_config, execute
from simmer.sweep.spec import SweepError, SweepSpec, load_sweep, success_condition, sweep_from_dict

__all__ = [
    "RunResult",
    "RunSpec",
    "SweepError",
    "SweepResult",
    "SweepSpec",
    "apply_overrides",
    "build_config",
    "dask_engine",
    "execute",
    "load_sweep",
    "local_pool",
    "run_sweep",
    "success_condition",
    "sweep_from_dict",
    "wilson_interval",
]
