"""The configuration reference, generated from the models so it can never go stale."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel
from pydantic_core import PydanticUndefined

from simmer.config.link import LinkSettings
from simmer.config.models import Settings
from simmer.config.project import GenerateSettings, ScenarioSettings, ScoreSettings, ZoneSettings
from simmer.devices import DeviceParams, device_kinds

PROJECT_TABLES = (ZoneSettings, ScenarioSettings, ScoreSettings)
"""The course project's tables, each listed in a section of its own."""


def _default(value: Any) -> str:
    if value is PydanticUndefined or value is None:
        return "—"
    if isinstance(value, (*PROJECT_TABLES, LinkSettings)):
        return "table below"
    if isinstance(value, BaseModel):
        return "{" + ", ".join(f"{k} = {v:g}" for k, v in value.model_dump().items()) + "}"
    if isinstance(value, tuple) and value and isinstance(value[0], tuple):
        return f"{len(value)} rows" if isinstance(value[0][0], int) else "see text"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, tuple):
        return "[" + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:g}"
    return f'"{value}"' if isinstance(value, str) else str(value)


def _table(model: type[BaseModel], skip: frozenset[str] = frozenset()) -> list[str]:
    lines = ["| key | default | meaning |", "| --- | --- | --- |"]
    for name, field in model.model_fields.items():
        if name in skip:
            continue
        base = DeviceParams.model_fields.get(name)
        described = field.description or (base.description if base else None) or ""
        description = described.replace("|", "\\|")
        lines.append(f"| `{name}` | `{_default(field.default)}` | {description} |")
    return lines


def reference_markdown() -> str:
    """Markdown listing every top-level key and every device kind's settings."""
    lines = [
        "# Configuration reference",
        "",
        "Generated from the models by `simmer keys --markdown`; do not edit by hand.",
        "Top-level keys use SimMeR's own names. Devices are tables named by their id:",
        "`[motors.m0]`, `[drives.w0]`, `[sensors.u0]`.",
        "",
        "## Top-level settings",
        "",
        *_table(Settings),
    ]
    lines += ["", "## `[maze]` (a generated maze, docs/mazes.md)", ""]
    lines += [(GenerateSettings.__doc__ or "").strip().splitlines()[0], ""]
    lines += _table(GenerateSettings)
    for key, model in (("zones", ZoneSettings), ("scenario", ScenarioSettings)):
        lines += ["", f"## `[{key}]` (the course project, docs/project.md)", ""]
        lines += [(model.__doc__ or "").strip().splitlines()[0], "", *_table(model)]
    lines += ["", "## `[score]` (the course project's rubric)", ""]
    lines += [(ScoreSettings.__doc__ or "").strip().splitlines()[0], "", *_table(ScoreSettings)]
    lines += ["", "## `[link]` (the link to the robot, docs/link.md)", ""]
    lines += [(LinkSettings.__doc__ or "").strip().splitlines()[0], "", *_table(LinkSettings)]
    for name, kind in sorted(device_kinds().items()):
        if kind.__module__.startswith("simmer."):
            lines += ["", f'## `type = "{name}"` ({kind.category})', ""]
            lines += [(kind.__doc__ or "").strip().splitlines()[0], ""]
            lines += _table(kind.Params)
    return "\n".join(lines) + "\n"
