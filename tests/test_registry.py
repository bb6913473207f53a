"""The device-kind registry and the plug-in interface (DESIGN §2)."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from simmer import Simulation
from simmer.devices import (
    Device,
    World,
    check_device_kind,
    device_kinds,
    register_device_kind,
)
from simmer.errors import ConfigError, DeviceKindError

from helpers import EXAMPLES, REPO, default_data, make_config

# Make sure the example plug-in is registered before the parametrisation below is collected.
Simulation.from_config(EXAMPLES / "tof_rover.toml")


@pytest.mark.parametrize("name", sorted(device_kinds()))
def test_every_registered_kind_honours_the_interface(name: str) -> None:
    kind = device_kinds()[name]
    check_device_kind(kind)
    assert kind.kind == name
    params = kind.Params.model_validate(_minimal_settings(kind))
    device = kind("t0", params, np.random.default_rng(0))
    assert device.outline.shape[1] == 2


def _minimal_settings(kind: type[Device]) -> dict[str, object]:
    if kind.category == "drive":
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


def test_plugin_kind_from_configuration_reads_the_wall() -> None:
    sim = Simulation.from_config(EXAMPLES / "tof_rover.toml")
    # t0 sits on the nose, 4 in ahead of (6, 42), facing the top wall.
    assert sim.command("t0") == pytest.approx([38.0], abs=1e-9)
    sim.command("w0-30")
    sim.run_until_idle()
    assert sim.command("t0") == pytest.approx([8.0], abs=1e-9)


def test_plugin_settings_are_validated(tmp_path: Path) -> None:
    shutil.copytree(EXAMPLES / "devices", tmp_path / "devices")
    path = tmp_path / "bad_tof.toml"
    path.write_text((EXAMPLES / "tof_rover.toml").read_text() + "max_rang = 3\n")
    with pytest.raises(
        ConfigError, match=r"sensors\.t0\.max_rang: unknown key \(did you mean 'max_range'"
    ):
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
