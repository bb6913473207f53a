"""Sweeps: run one controller over many seeds and configuration settings, in parallel, and
show how often it succeeds and how it fails (``simmer sweep SWEEP.toml``).

:func:`load_sweep` reads a sweep file (:mod:`simmer.sweep.spec`), :func:`run_sweep` runs it on
a process pool or a Dask cluster (:mod:`simmer.sweep.engine`), each run described by a
picklable :class:`RunSpec` and carried out in a worker (:mod:`simmer.sweep.runs`, on a
simulation kept warm there), and writes ``results.csv``, the kept runs' folders and
``summary.md`` (:mod:`simmer.sweep.results`, :mod:`simmer.sweep.pictures`). Success and the
kinds of failure are in :mod:`simmer.sweep.success`.
"""

from simmer.config.overrides import apply_overrides
from simmer.sweep.engine import DaskExecutor, SweepResult, dask_engine, local_pool, run_sweep
from simmer.sweep.results import wilson_interval
from simmer.sweep.runs import RunResult, RunSpec, build_config
from simmer.sweep.spec import Distribution, SweepSpec, load_sweep, sweep_from_dict
from simmer.sweep.success import FAILURES, failure_kind, success_condition

__all__ = [
    "FAILURES",
    "DaskExecutor",
    "Distribution",
    "RunResult",
    "RunSpec",
    "SweepResult",
    "SweepSpec",
    "apply_overrides",
    "build_config",
    "dask_engine",
    "failure_kind",
    "load_sweep",
    "local_pool",
    "run_sweep",
    "success_condition",
    "sweep_from_dict",
    "wilson_interval",
]
