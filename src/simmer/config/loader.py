"""Load and summarise configurations: a TOML file, an original SimMeR ``config.py`` (read by
:mod:`simmer.config.simmer_py`) or the built-in default, each validated by
:mod:`simmer.config.validate`.
"""

from __future__ import annotations

import tomllib
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache
from importlib.resources import files
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from simmer.config import simmer_py
from simmer.config.models import DEVICE_GROUPS, SimConfig
from simmer.config.toml_errors import toml_issue, with_lines
from simmer.config.validate import ORIGINAL_RUNS, config_from_dict
from simmer.errors import ConfigError, ConfigIssue

BUILTIN_SOURCE = "<built-in default>"
MAX_FILE_BYTES = 1_000_000
"""Largest configuration file read: the lab's are 3 kB, and the walls of the largest maze
allowed (500 x 500 cells) take 750 kB; a larger file is the wrong file, and reading it would
take minutes and gigabytes."""

__all__ = [  # config_from_dict and ORIGINAL_RUNS live in validate; named here for older imports
    "BUILTIN_SOURCE",
    "MAX_FILE_BYTES",
    "ORIGINAL_RUNS",
    "config_from_dict",
    "config_from_toml",
    "default_config",
    "describe_noise",
    "load_config",
    "noisy_devices",
    "placed_issues",
    "read_config_data",
    "summarize",
]


def load_config(path: str | Path | None = None) -> SimConfig:
    """Load a configuration file (TOML or SimMeR ``config.py``); None gives the built-in default.

    Whatever is wrong with the file is a :class:`ConfigError` naming it, so ``simmer check``
    and ``simmer run`` can say so in one line.
    """
    if path is None:
        return default_config()
    path = _checked_file(path)
    with _unreadable_as_config_error(path):
        if path.suffix == ".py":
            return simmer_py.load_simmer_py(path)
        text = path.read_text(encoding="utf-8")
        return config_from_toml(text, str(path), path.parent)


def as_config(config: SimConfig | str | Path | None) -> SimConfig:
    """A configuration given as itself, as a file to load, or None (the built-in default)."""
    return config if isinstance(config, SimConfig) else load_config(config)


def read_config_data(path: str | Path) -> tuple[dict[str, Any], bool]:
    """A configuration file's data before validation, with the same checks and messages as
    :func:`load_config`, and whether it is an original SimMeR ``config.py`` (validate it with
    ``config_from_dict(..., original=True)`` then). For tools that change settings first."""
    path = _checked_file(path)
    with _unreadable_as_config_error(path):
        if path.suffix == ".py":
            return simmer_py.read_simmer_py(path).data, True
        return _toml_data(path.read_text(encoding="utf-8"), str(path)), False


def _checked_file(path: str | Path) -> Path:
    """``path``, if it is a file small enough to be a configuration (else a ConfigError)."""
    path = Path(path)
    if path.exists() and not path.is_file():
        raise ConfigError(
            path,
            [
                ConfigIssue(
                    "",
                    "is not a regular file (a folder, a device or a pipe); give a "
                    "configuration file (.toml or config.py)",
                )
            ],
        )
    if not path.is_file():
        raise ConfigError(
            path, [ConfigIssue("", "no such file; check the path (run `simmer check FILE`)")]
        )
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise ConfigError(
            path,
            [
                ConfigIssue(
                    "",
                    f"is {size:,} bytes, more than any configuration ({MAX_FILE_BYTES:,} at "
                    "most: even a 500 x 500 maze takes 750,000); is this the right file?",
                )
            ],
        )
    return path


@contextmanager
def _unreadable_as_config_error(path: Path) -> Iterator[None]:
    """Turn what a file can make Python raise, beyond the problems validation reports, into a
    :class:`ConfigError`: unreadable bytes, lists nested deeper than Python follows (in a
    config.py), or more data than memory holds."""
    try:
        yield
    except (OSError, UnicodeDecodeError) as exc:
        message = f"cannot read the file: {exc}; save it as UTF-8 text"
        raise ConfigError(path, [ConfigIssue("", message)]) from None
    except RecursionError:
        message = "lists or tables are nested too deeply to read; no setting nests more than 3"
        raise ConfigError(path, [ConfigIssue("", message)]) from None
    except MemoryError:
        message = "holds more data than fits in memory; no configuration needs that much"
        raise ConfigError(path, [ConfigIssue("", message)]) from None


def placed_issues(path: str | Path, issues: list[ConfigIssue]) -> list[ConfigIssue]:
    """Problems found in a loaded TOML file (a device failing its first call) with the line
    of each key, as validation's have them."""
    path = Path(path)
    if path.suffix == ".py" or not path.is_file():
        return issues
    with _unreadable_as_config_error(path):
        return with_lines(issues, path.read_text(encoding="utf-8"))


@cache
def default_config() -> SimConfig:
    """The built-in default: SimMeR's maze, block and start pose with the lab rover, noise off."""
    text = files("simmer").joinpath("data/default.toml").read_text(encoding="utf-8")
    return config_from_toml(text, BUILTIN_SOURCE, Path.cwd())


def config_from_toml(text: str, source: str, base_dir: Path) -> SimConfig:
    """Parse TOML text and validate it (see :func:`config_from_dict`).

    A file that is not TOML gets one issue in plain words, with its line (a key or table
    written twice names both lines: :mod:`simmer.config.toml_errors`).
    """
    data = _toml_data(text, source)
    if "maze" in data and "walls" in data:
        message = "sets both maze and walls; a maze supplies the walls: remove one of the two"
        raise ConfigError(source, with_lines([ConfigIssue("walls", message)], text))
    try:
        return config_from_dict(data, source, base_dir)
    except ConfigError as exc:
        raise ConfigError(source, with_lines(exc.issues, text)) from None


def _toml_data(text: str, source: str) -> dict[str, Any]:
    """Parse TOML text; a ConfigError in plain words, with the line, if it is not TOML."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(source, [toml_issue(exc, text)]) from None
    except RecursionError:
        message = "lists or tables are nested too deeply to read; no setting nests more than 3"
        raise ConfigError(source, [ConfigIssue("", f"not valid TOML: {message}")]) from None


# ----------------------------------------------------------------------------- summary


def summarize(
    config: SimConfig, *, seed: int | None = None, ports: tuple[int, int, int] | None = None
) -> str:
    """One paragraph describing what a configuration sets up (for ``simmer check`` and the
    start of ``simmer run``): the noise as configured, with ``seed`` (default: the
    configuration's), and the three ``ports`` (two-port message and reply, persistent) if given
    (a run says the ports it actually serves on its own lines)."""
    s = config.settings
    rows, cols = len(s.walls), len(s.walls[0])
    length = s.wall_segment_length
    groups: dict[str, list[str]] = {group: [] for group in DEVICE_GROUPS}
    for spec in config.devices:
        groups[spec.group].append(spec.id if spec.group != "sensors" else f"{spec.id} {spec.kind}")
    parts = [
        f"{len(groups[g])} {g[:-1] if len(groups[g]) == 1 else g}"
        + (f" ({', '.join(groups[g])})" if groups[g] else "")
        for g in DEVICE_GROUPS
    ]
    served = (
        f"; on {s.host} ports {ports[0]} (two-port messages), {ports[1]} (two-port replies) "
        f"and {ports[2]} (persistent, simmer.client)"
        if ports
        else ""
    )
    block = (
        f"at {list(s.block_position)}"
        if s.scenario.block == "config"
        else (
            "drawn inside the loading zone"
            if s.scenario.block == "random"
            else f"at {s.scenario.block}"
        )
    )
    start = f"at {list(s.robot_start_position)} heading {s.robot_start_rotation:g} deg"
    if s.scenario.start != "config":
        start = {"random": "in a start cell drawn", "open": "in an open cell drawn"}.get(
            s.scenario.start, f"in cell {s.scenario.start}"
        )
    return (
        f"Maze of {cols} x {rows} cells of {length:g} in "
        f"({cols * length:g} x {rows * length:g} in), "
        f"floor tiles of {s.floor_segment_length:g} in from seed {s.floor_seed}. "
        f"Block of {s.block_size:g} in {block}. "
        f"Robot starting {start} "
        f"with {', '.join(parts)}. "
        f"Noise: {describe_noise(config, seed)}. {s.frame_rate:g} steps/s{served}, replies "
        f"{config.reply_codec().describe()}." + _link(config) + _project(config)
    )


def _link(config: SimConfig) -> str:
    """The summary's words on the link model (none when it is off)."""
    p = config.settings.link.resolved()
    if p is None:
        return ""
    return (
        f" Link model {p.preset}: {p.baud:g} baud, {p.latency * 1000:g} ms latency, "
        f"{p.loss:g} of bytes lost (docs/link.md)."
    )


def noisy_devices(config: SimConfig) -> dict[str, list[str]]:
    """The devices with noise switched on, and which of their settings (``error``, ``bias``)
    are not zero; drive biases drawn at start (``rand_bias``) count as each drive's bias."""
    settings = config.settings
    drawn = settings.rand_bias and any(settings.bias_strength)
    found: dict[str, list[str]] = {}
    for spec in config.devices:
        own = getattr(spec.params, "noise_keys", None)
        if callable(own):  # a kind whose noise settings have other names (lidar, tof, imu, encoder)
            if names := own():
                found[spec.id] = names
            continue
        for name in ("error", "bias"):
            value = getattr(spec.params, name, 0.0)
            values = value.model_dump().values() if isinstance(value, BaseModel) else [value]
            if any(v != 0 for v in values) or (drawn and name == "bias" and spec.group == "drives"):
                found.setdefault(spec.id, []).append(name)
    return found


def describe_noise(config: SimConfig, seed: int | None = None) -> str:
    """``none (every error and bias is 0)``, or which devices are noisy and the seed."""
    noisy = noisy_devices(config)
    if not noisy:
        return "none (every error and bias is 0)"
    s = config.settings
    devices = ", ".join(f"{device} {' and '.join(names)}" for device, names in noisy.items())
    if s.rand_error:
        draw = "fresh each run" + (f" (this run's: seed {seed})" if seed is not None else "")
    else:
        draw = f"repeatable, seed {s.run_seed(seed)}"
    drawn = (
        f"; drive biases drawn at start (strength {list(s.bias_strength)})" if s.rand_bias else ""
    )
    return f"{devices}; {draw}{drawn}"


def _project(config: SimConfig) -> str:
    """The zones and the target, for a project run or a configuration that names zones."""
    from simmer.config.project import ZoneSettings
    from simmer.config.zones import Zones, project_run

    s = config.settings
    if not project_run(config) and s.zones == ZoneSettings():
        return ""
    target = "drawn from the seed" if s.scenario.target == "random" else s.scenario.target
    return f" {Zones.from_settings(s).describe()} Target zone: {target}."
