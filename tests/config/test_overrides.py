"""Overrides take one route: dotted keys set in a configuration's data, validated as a file's
data is (``simmer.config.overrides``), from the command line as from a sweep's grid."""

from __future__ import annotations

import pytest

from simmer import load_config
from simmer.config import apply_overrides, config_from_dict, with_overrides
from simmer.config.loader import read_config_data
from simmer.errors import ConfigError

from helpers import EXAMPLES, noisy_config

BUMPER_ROVER = EXAMPLES / "bumper_rover.toml"


def test_a_loaded_configuration_takes_device_overrides_too() -> None:
    config = noisy_config()
    changed = with_overrides(config, {"drives.w0.error.x": 0.25, "frame_rate": 30})
    assert changed.device("w0").params.error.x == 0.25  # type: ignore[attr-defined]
    assert changed.settings.frame_rate == 30
    before, after = config.device("w0").params, changed.device("w0").params
    assert after.error.y == before.error.y  # type: ignore[attr-defined]
    assert changed.source == config.source


def test_an_override_is_checked_as_a_file_is() -> None:
    config = noisy_config()
    with pytest.raises(ConfigError) as caught:
        with_overrides(config, {"drives.w0.error.x": "lots"}, "the command line")
    assert str(caught.value).startswith("the command line")
    assert "drives.w0.error.x" in str(caught.value)


def test_a_plugin_device_takes_overrides_as_a_sweep_gives_them() -> None:
    loaded = load_config(BUMPER_ROVER)
    changed = with_overrides(loaded, {"sensors.b0.reach": 2.0})
    assert changed.device("b0").params.reach == 2.0  # type: ignore[attr-defined]
    assert changed.kinds == loaded.kinds  # its plug-in's kind, found again
    data, original = read_config_data(BUMPER_ROVER)
    apply_overrides(data, [("sensors.b0.reach", 2.0)])
    assert (
        config_from_dict(data, str(BUMPER_ROVER), BUMPER_ROVER.parent, original=original) == changed
    )
