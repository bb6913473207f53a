"""Configuration: typed models, the TOML loader, the built-in default."""

from simmer.config.loader import (
    config_from_dict,
    config_from_toml,
    default_config,
    load_config,
    summarize,
)
from simmer.config.models import DeviceSpec, Settings, SimConfig

__all__ = [
    "DeviceSpec",
    "Settings",
    "SimConfig",
    "config_from_dict",
    "config_from_toml",
    "default_config",
    "load_config",
    "summarize",
]
