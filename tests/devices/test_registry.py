"""The device-kind registry and the plug-in interface (DESIGN §2)."""

from __future__ import annotations

import math
import re
import shutil
import sys
from collections.abc import Iterator
from importlib.metadata import EntryPoint
from pathlib import Path

import numpy as np
import pytest

from simmer import Simulation
from simmer.devices import (
    Device,
    World,
    check_device_kind,
    device_kinds,
    get_device_kind,
    register_device_kind,
    registry,
)
from simmer.errors import ConfigError, DeviceKindError

from helpers import EXAMPLES, REPO, default_data, make_config

# Make sure the example plug-in is registered before the parametrisation below is collected.
Simulation.from_config(EXAMPLES / "bumper_rover.toml")


@pytest.mark.parametrize("name", sorted(device_kinds()))
def test_every_registered_kind_honours_the_interface(name: str) -> None:
    kind = device_kinds()[name]
    check_device_kind(kind)
    assert kind.kind == name
    params = kind.Params.model_validate(_minimal_settings(kind))
    device = kind("t0", params, np.random.default_rng(0))
    assert device.outline.shape[1] == 2


def _minimal_settings(kind: type[Device]) -> dict[str, object]:
    if kind.category == "drive" and "velocity" in kind.Params.model_fields:
        return {"velocity": [0, 1]}
    return {}


def test_builtin_kinds_are_registered() -> None:
    assert {"motor", "drive", "ultrasonic", "gyroscope", "compass", "infrared"} <= set(
        device_kinds()
    )


class _Good(Device):
    def simulate(self, value: float, world: World) -> float:
        return 1.0


def test_duplicate_name_is_an_error() -> None:
    with pytest.raises(DeviceKindError, match="already registered"):
        register_device_kind("ultrasonic", _Good)


def test_interface_checker_names_what_is_missing() -> None:
    class NoSimulate(Device):
        pass

    class BadCategory(_Good):
        category = "wheel"  # type: ignore[assignment]

    class BadParams(_Good):
        Params = dict  # type: ignore[assignment]

    with pytest.raises(DeviceKindError, match="override simulate"):
        check_device_kind(NoSimulate)
    with pytest.raises(DeviceKindError, match="category"):
        check_device_kind(BadCategory)
    with pytest.raises(DeviceKindError, match="Params"):
        check_device_kind(BadParams)
    with pytest.raises(DeviceKindError, match="not a subclass"):
        check_device_kind(object)


def test_plugin_kind_from_configuration_feels_the_wall() -> None:
    sim = Simulation.from_config(EXAMPLES / "bumper_rover.toml")
    # b0 sits on the nose, 4 in ahead of (6, 42), facing the top wall 38 in away.
    assert sim.command("b0") == [0.0]
    sim.command("w0-37.9")  # the bar 0.1 in from the wall: within its reach of 0.25 in
    sim.run_until_idle()
    assert sim.command("b0") == [1.0]
    sim.command("w0--0.2")  # 0.3 in: out of reach again
    sim.run_until_idle()
    assert sim.command("b0") == [0.0]


def test_plugin_settings_are_validated(tmp_path: Path) -> None:
    shutil.copytree(EXAMPLES / "devices", tmp_path / "devices")
    path = tmp_path / "bad_bumper.toml"
    path.write_text((EXAMPLES / "bumper_rover.toml").read_text() + "reac = 3\n")
    with pytest.raises(ConfigError, match=r"sensors\.b0\.reac: unknown key \(did you mean 'reach'"):
        Simulation.from_config(path)


def test_the_documented_bumper_example_works(tmp_path: Path) -> None:
    doc = (REPO / "docs" / "devices.md").read_text()
    code = re.search(r"```python\n(.*?)```", doc, re.S)
    assert code is not None
    plugin = tmp_path / "bumper.py"
    plugin.write_text(code.group(1).replace('"bumper"', '"doc_bumper"'))
    data = default_data()
    data["plugins"] = [str(plugin)]
    data["sensors"]["b0"] = {"type": "doc_bumper", "position": [0, 4], "reach": 0.5}
    sim = Simulation(make_config(data))
    assert sim.command("b0") == [0.0]
    sim.command("w0-40")
    sim.run_until_idle()
    assert sim.command("b0") == [1.0]


def test_plugin_error_names_the_line(tmp_path: Path) -> None:
    plugin = tmp_path / "broken.py"
    plugin.write_text("x = 1\nraise RuntimeError('oops')\n")
    data = default_data() | {"plugins": [str(plugin)]}
    with pytest.raises(ConfigError, match=r"plugins\[0\]: importing .*broken.py failed at line 2"):
        make_config(data)


def test_user_devices_share_the_seeded_generator(tmp_path: Path) -> None:
    class Noisy(Device):
        def simulate(self, value: float, world: World) -> float:
            return float(self.rng.normal())

    register_device_kind("test_noisy", Noisy, replace=True)
    data = default_data()
    data["sensors"]["n0"] = {"type": "test_noisy"}
    first = Simulation(make_config(data), seed=3).command("n0,n0")
    again = Simulation(make_config(data), seed=3).command("n0,n0")
    assert first == again
    assert not math.isnan(first[0])


def test_configuration_reference_is_up_to_date() -> None:
    from simmer.config.reference import reference_markdown

    committed = (REPO / "docs" / "configuration.md").read_text(encoding="utf-8")
    assert committed == reference_markdown(), "run: simmer keys --markdown > docs/configuration.md"


LAZY_KIND = """
from simmer.devices import Device, World


class Lazy(Device):
    def simulate(self, value: float, world: World) -> float:
        return 7.0
"""


@pytest.fixture
def own_registry(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[Path]:
    """A registry this test may change, and a folder on sys.path; both restored afterwards
    (with the modules imported from that folder)."""
    monkeypatch.setattr(registry, "_KINDS", dict(registry._KINDS))
    monkeypatch.syspath_prepend(str(tmp_path))
    yield tmp_path
    for name, module in list(sys.modules.items()):
        if Path(getattr(module, "__file__", None) or "/").is_relative_to(tmp_path):
            del sys.modules[name]


def test_a_kind_registered_by_name_is_imported_on_first_use(own_registry: Path) -> None:
    (own_registry / "test_lazy_kinds.py").write_text(LAZY_KIND)
    assert register_device_kind("test_lazy", "test_lazy_kinds:Lazy") == "test_lazy_kinds:Lazy"
    assert "test_lazy_kinds" not in sys.modules
    kind = get_device_kind("test_lazy")
    assert kind is not None
    assert kind.__name__ == "Lazy"
    assert kind.kind == "test_lazy"
    assert get_device_kind("test_lazy") is kind
    register_device_kind("test_lazy", "test_lazy_kinds:Lazy")  # the same class again: fine
    with pytest.raises(DeviceKindError, match="already registered by test_lazy_kinds:Lazy"):
        register_device_kind("test_lazy", "test_lazy_kinds:Other")


def test_a_kind_that_cannot_be_imported_says_which(own_registry: Path) -> None:
    register_device_kind("test_missing", "test_no_such_module:Gone")
    register_device_kind("test_not_a_device", "math:pi")
    with pytest.raises(DeviceKindError, match="'test_missing': cannot import test_no_such_mod"):
        get_device_kind("test_missing")
    with pytest.raises(DeviceKindError, match=r"3\.14.* is not a subclass of simmer\.devices"):
        get_device_kind("test_not_a_device")


def test_installed_kinds_are_imported_on_first_use(
    own_registry: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (own_registry / "test_installed_kinds.py").write_text(LAZY_KIND)
    found = [EntryPoint("test_installed", "test_installed_kinds:Lazy", registry.ENTRY_POINT_GROUP)]
    monkeypatch.setattr(registry, "entry_points", lambda group: found)
    monkeypatch.setattr(registry, "_ENTRY_POINTS_LOADED", False)
    assert get_device_kind("motor") is not None
    assert "test_installed_kinds" not in sys.modules
    kind = get_device_kind("test_installed")
    assert kind is not None
    assert kind.kind == "test_installed"
