"""The public API (issue 29): each public module's ``__all__`` is pinned here, every name in it
exists and says what it is, none comes from an internal module by accident, every module is
either public or internal (``simmer._api``), and docs/api.md is what scripts/api_docs.py
writes. A change to a pinned list is a change to the API: the CHANGELOG says so."""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path
from types import ModuleType

import pytest

import simmer
from simmer._api import FROM_INTERNAL, INTERNAL, PUBLIC

from helpers import REPO

EXPORTED = {
    "simmer": [
        "ConfigError",
        "Device",
        "DeviceParams",
        "Pose",
        "SimConfig",
        "SimmerError",
        "Simulation",
        "__version__",
        "load_config",
        "register_device_kind",
        "replay",
        "with_overrides",
    ],
    "simmer.client": [
        "Address",
        "AskLink",
        "Client",
        "ClockLink",
        "Link",
        "Scan",
        "Scheme",
        "SerialLink",
        "StreamLink",
        "TwoPortLink",
        "address",
        "connect",
    ],
    "simmer.devices": [
        "Axes",
        "Circle",
        "Compass",
        "CompassParams",
        "Device",
        "DeviceKinds",
        "DeviceParams",
        "Drive",
        "DriveParams",
        "Encoder",
        "EncoderParams",
        "Gyroscope",
        "GyroscopeParams",
        "Imu",
        "ImuParams",
        "Infrared",
        "InfraredParams",
        "Lidar",
        "LidarParams",
        "Motion",
        "Motor",
        "MotorParams",
        "Segment",
        "Shape",
        "TimeOfFlight",
        "TimeOfFlightParams",
        "Ultrasonic",
        "UltrasonicParams",
        "Vec2",
        "World",
        "check_device_kind",
        "device_kinds",
        "get_device_kind",
        "heading_vector",
        "register_device_kind",
    ],
    "simmer.ending": ["RunEnd"],
    "simmer.errors": [
        "BatchError",
        "BusClosed",
        "ClientError",
        "CommandError",
        "ConfigError",
        "ConfigIssue",
        "ConnectionFailed",
        "DeviceKindError",
        "ExitCalled",
        "FolderExists",
        "GenerateError",
        "LimitReached",
        "PlotError",
        "ProgramNotFound",
        "ReplayError",
        "ReplyTimeout",
        "ScenarioError",
        "SimmerError",
        "SweepError",
        "SweepStopped",
        "UnsafeOutput",
        "UntrustedRun",
        "WallLimitReached",
        "WrongThread",
    ],
    "simmer.pose": ["Pose", "Vec2"],
    "simmer.record": [
        "EventLog",
        "LoadedRun",
        "RunRecorder",
        "TRACE_RATE",
        "TraceWriter",
        "load_run",
        "read_events",
        "read_manifest",
        "read_scans",
        "retrace",
        "write_report_md",
    ],
    "simmer.sweep": [
        "DaskExecutor",
        "Distribution",
        "FAILURES",
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
    ],
    "simmer.batch": ["Batch", "BatchError", "Model"],
    "simmer.gym": [
        "DISCRETE_MOVES",
        "ENVIRONMENTS",
        "LAB_NOISE",
        "MazeEnv",
        "MazeVectorEnv",
        "PROJECT_MOVES",
        "ProjectEnv",
        "register_environments",
    ],
}
"""Each public module's names, sorted."""


@pytest.fixture(scope="module")
def api_docs() -> ModuleType:
    """scripts/api_docs.py, loaded as a module."""
    spec = importlib.util.spec_from_file_location("api_docs", REPO / "scripts" / "api_docs.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_public_modules_are_pinned() -> None:
    assert list(EXPORTED) == list(PUBLIC)


@pytest.mark.parametrize("module", PUBLIC)
def test_all_is_exactly_the_pinned_names(module: str) -> None:
    exported = importlib.import_module(module).__all__
    assert len(set(exported)) == len(exported), f"{module}.__all__ names one twice"
    assert sorted(exported) == EXPORTED[module], (
        f"{module}.__all__ changed: a change to the public API (update EXPORTED, the CHANGELOG "
        "and docs/api.md)"
    )


@pytest.mark.parametrize("module", PUBLIC)
def test_every_public_name_exists_and_says_what_it_is(module: str, api_docs: ModuleType) -> None:
    loaded = importlib.import_module(module)
    missing = [name for name in loaded.__all__ if not hasattr(loaded, name)]
    assert not missing, f"{module}.__all__ names what it does not have: {missing}"
    undocumented = [name for name in loaded.__all__ if not api_docs.docstring(module, name)]
    assert not undocumented, f"no docstring in {module}: {undocumented}"


@pytest.mark.parametrize("module", PUBLIC)
def test_no_public_name_comes_from_an_internal_module_by_accident(
    module: str, api_docs: ModuleType
) -> None:
    """A name is defined in its module (or a module inside its package), in another public
    module, or taken from an internal one on purpose (``FROM_INTERNAL``)."""
    public = [name for name in PUBLIC if name != "simmer"]  # the root holds every module
    taken = set(FROM_INTERNAL.get(module, ()))
    stray = {}
    for name in importlib.import_module(module).__all__:
        where = api_docs.defined_in(module, name)
        inside = where == module or any(api_docs.within(where, other) for other in public)
        if inside == (name in taken):
            stray[name] = where
    assert not stray, (
        f"{module}: names from an internal module not in FROM_INTERNAL, or listed there but "
        f"not from one: {stray}"
    )


def test_from_internal_lists_only_exported_names() -> None:
    for module, names in FROM_INTERNAL.items():
        assert set(names) <= set(EXPORTED[module]), module


def test_every_module_is_public_or_internal() -> None:
    """Every top-level module and package of simmer is listed once, in PUBLIC or INTERNAL."""
    source = Path(simmer.__file__).parent
    units = {
        f"simmer.{path.stem}"
        for path in source.iterdir()
        if (path.suffix == ".py" and path.stem != "__init__")
        or (path.is_dir() and (path / "__init__.py").exists())
    }
    public = set(PUBLIC) - {"simmer"}
    listed = public | set(INTERNAL)
    assert not public & set(INTERNAL), "both public and internal"
    assert units == listed, f"unlisted: {sorted(units - listed)}; gone: {sorted(listed - units)}"
    assert list(INTERNAL) == sorted(INTERNAL)


def test_the_package_docstring_names_the_public_modules() -> None:
    doc = simmer.__doc__ or ""
    assert all(f":mod:`{module}`" in doc for module in PUBLIC if module != "simmer")
    assert "internal and may change" in doc


def test_docs_api_md_is_up_to_date(api_docs: ModuleType) -> None:
    written = (REPO / "docs" / "api.md").read_text(encoding="utf-8")
    assert written == api_docs.render(), (
        f"docs/api.md is out of date: run `{api_docs.COMMAND}` (with the .venv's python)"
    )
