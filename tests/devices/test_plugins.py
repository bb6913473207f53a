"""A configuration's plug-ins register their kinds for that configuration alone."""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest

from simmer import Simulation, load_config
from simmer.devices import device_kinds
from simmer.errors import ConfigError

BEACON = '''\
"""A sensor that always reads {reading}."""
from simmer.devices import Device, World, register_device_kind


class Beacon(Device):
    def simulate(self, value: float, world: World) -> float:
        return {reading}


register_device_kind("test_beacon", Beacon)
'''


def beacon_config(folder: Path, reading: float, plugins: tuple[str, ...] = ("beacon.py",)) -> Path:
    """A configuration in ``folder`` whose plug-in defines kind ``test_beacon`` reading
    ``reading``, with one such sensor, ``b0``."""
    folder.mkdir(exist_ok=True)
    (folder / "beacon.py").write_text(BEACON.format(reading=reading), encoding="utf-8")
    path = folder / "robot.toml"
    listed = ", ".join(f'"{entry}"' for entry in plugins)
    path.write_text(f'plugins = [{listed}]\n\n[sensors.b0]\ntype = "test_beacon"\n')
    return path


def test_two_configurations_each_have_their_own_kind_of_one_name(tmp_path: Path) -> None:
    first = load_config(beacon_config(tmp_path / "first", 1.5))
    second = load_config(beacon_config(tmp_path / "second", 2.5))
    assert Simulation(first).command("b0") == pytest.approx([1.5])
    assert Simulation(second).command("b0") == pytest.approx([2.5])
    assert Simulation(first).command("b0") == pytest.approx([1.5])  # the second changed nothing
    assert "test_beacon" not in device_kinds()
    copy = pickle.loads(pickle.dumps(second))
    assert copy == second
    assert Simulation(copy).command("b0") == pytest.approx([2.5])


def test_two_plugins_of_one_configuration_may_not_share_a_kind(tmp_path: Path) -> None:
    path = beacon_config(tmp_path, 1.0, ("beacon.py", "other.py"))
    (tmp_path / "other.py").write_text(BEACON.format(reading=2.0), encoding="utf-8")
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert (
        "plugins[1]: other.py registers device kind 'test_beacon', as beacon.py does; "
        "rename one of the two"
    ) in str(caught.value)


def test_a_plugin_named_twice_is_loaded_once(tmp_path: Path) -> None:
    path = beacon_config(tmp_path, 3.0, ("beacon.py", "./beacon.py"))
    assert Simulation(load_config(path)).command("b0") == pytest.approx([3.0])
