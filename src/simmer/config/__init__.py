"""Configuration: typed models, the loaders (TOML, SimMeR config.py), validation, the
built-in default."""

from simmer.config.loader import config_from_toml, default_config, load_config, summarize
from simmer.config.models import DeviceSpec, Settings, SimConfig
from simmer.config.overrides import apply_overrides, with_overrides
from simmer.config.validate import config_from_dict

__all__ = [
    "DeviceSpec",
    "Settings",
    "SimConfig",
    "apply_overrides",
    "config_from_dict",
    "config_from_toml",
    "default_config",
    "load_config",
    "summarize",
    "with_overrides",
]
