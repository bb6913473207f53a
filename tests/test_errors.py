"""The exception tree: every exception class SimMeR defines lives in ``simmer/errors.py``, and
its module docstring draws each of them."""

from __future__ import annotations

import importlib
import inspect
import pickle
import pkgutil

import simmer
import simmer.errors
from simmer.errors import (
    BusClosed,
    FolderExists,
    LimitReached,
    PlotError,
    ScenarioError,
    SimmerError,
    SweepError,
    SweepStopped,
)


def exception_classes() -> list[tuple[str, type[BaseException]]]:
    """(module, class) for every exception class defined in a module of simmer."""
    found = []
    for info in pkgutil.walk_packages(simmer.__path__, "simmer."):
        if info.name.endswith("__main__"):
            continue  # runs the command line when imported
        module = importlib.import_module(info.name)
        for value in vars(module).values():
            if (
                inspect.isclass(value)
                and issubclass(value, BaseException)
                and value.__module__ == info.name
            ):
                found.append((info.name, value))
    return found


def test_every_exception_class_is_defined_in_errors_py() -> None:
    found = exception_classes()
    outside = [f"{module}.{cls.__name__}" for module, cls in found if module != "simmer.errors"]
    assert outside == [], "define these in src/simmer/errors.py (and draw them in its docstring)"
    assert len(found) >= 19  # the walk reached the modules (ui/ too, through pygame's dummy)


def test_the_docstring_draws_every_class() -> None:
    doc = simmer.errors.__doc__ or ""
    missing = [cls.__name__ for _, cls in exception_classes() if cls.__name__ not in doc]
    assert missing == []


def test_value_errors_stay_value_errors_and_join_the_tree() -> None:
    for cls in (SweepError, FolderExists):
        assert issubclass(cls, SimmerError)
        assert issubclass(cls, ValueError)
    scenario = ScenarioError("scenario.start", "no such cell")
    assert isinstance(scenario, ValueError)
    assert isinstance(scenario, SimmerError)
    assert (scenario.key, str(scenario)) == ("scenario.start", "scenario.start: no such cell")
    assert issubclass(PlotError, SimmerError)
    assert issubclass(BusClosed, SimmerError)


def test_signals_that_stop_a_run_are_not_simmer_errors() -> None:
    """A policy's ``except SimmerError`` must not swallow its run's limit, nor Ctrl-C."""
    assert not issubclass(LimitReached, SimmerError)
    assert issubclass(SweepStopped, KeyboardInterrupt)


def test_a_sweep_error_crosses_to_a_worker_and_back() -> None:
    assert str(pickle.loads(pickle.dumps(SweepError("bad sweep")))) == "bad sweep"
