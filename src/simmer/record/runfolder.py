"""A run folder: what one run did, kept to look at again, replay and report.

``simmer run --record DIR`` (and :class:`RunRecorder` from Python) keeps in DIR:

- ``manifest.json``, written at the start: SimMeR's version, the whole resolved configuration
  (every setting and device, as data, with the file it came from), the seed, the clock, speed
  and link delay, the control program's command line, the platform and the start time;
  :func:`load_run` rebuilds the configuration from it;
- ``events.jsonl``, every event as it happens (:mod:`simmer.record.eventlog`);
- ``trace.csv``, the true pose and the sensors' last readings (:mod:`simmer.record.trace`);
- ``scans.csv``, when the robot has a LiDAR: every whole scan (:mod:`simmer.record.scans`);
  these three are read back only by :mod:`simmer.record.reader`;
- ``report.json`` and ``report.md``, written when the run ends: its outcome (the Task 2 time,
  collisions, path length, commands, NaN replies, final pose) and its facts (seed, length, how
  it ended); ``report.md`` is in plain words for a lab report and shows ``path.png`` and
  ``sensors.png`` when ``simmer plot DIR`` has drawn them (:func:`write_report_md`).

The recorder is an observer of the simulation: it writes in the simulation's own thread, as
each event happens, and nothing else touches the simulation for it. A run is replayable from
its folder (:func:`load_run`, :func:`simmer.world.replay.replay`) when it was recorded from its
first step.
"""

from __future__ import annotations

import json
import math
import os
import platform
import re
import sys
import time
from collections.abc import Callable, Sequence
from contextlib import suppress
from dataclasses import replace
from datetime import datetime
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from types import TracebackType
from typing import Any, NamedTuple

import simmer
from simmer.config.models import DEVICE_GROUPS, SimConfig
from simmer.config.validate import DEFAULT_KIND, config_from_dict
from simmer.devices.registry import BUILTIN_KINDS
from simmer.ending import RunEnd
from simmer.errors import UntrustedRun
from simmer.geometry import Pose, wrap_degrees
from simmer.options import MAX_RECORDING_BYTES, RunOptions
from simmer.record.eventlog import EventLog, RecordingBudget, stop_reason
from simmer.record.reader import EVENTS, SCANS, TRACE, read_events
from simmer.record.safefile import check_target, write_text
from simmer.record.scans import ScanWriter, lidar_ids
from simmer.record.trace import TRACE_RATE, TraceWriter, trace_columns
from simmer.untrusted import parse_json, read_at_most
from simmer.world.events import Event
from simmer.world.outcome import Outcome
from simmer.world.replay import Replayed, feed
from simmer.world.simulation import Simulation

FORMAT = 1
"""Version of the run folder's layout, in the manifest; a reader refuses a newer one."""
MANIFEST = "manifest.json"
REPORT_JSON = "report.json"
REPORT_MD = "report.md"
PLOTS = (
    ("path.png", "The robot's true path"),
    ("sensors.png", "Sensor readings against time"),
    ("localization.png", "The program's estimate against the truth"),
    ("scans.png", "Every LiDAR scan point over the maze"),
    ("scan.png", "One LiDAR scan, over the maze and as read"),
)
"""The pictures ``simmer plot DIR`` draws, which report.md shows when they exist."""
MAX_JSON_BYTES = 16_000_000
"""Largest ``manifest.json`` or ``report.json`` read: a manifest holds the largest maze allowed
in under 1 MB; a larger file is not one SimMeR wrote, and parsing it costs seconds and memory."""
MAX_REPORT_CHARS = 200
"""Characters of one text (a program's command line, a configuration's name) that report.md
copies from a run folder's files; the rest is cut ("..."): a manifest may hold megabytes."""
MARKDOWN_SPECIAL = frozenset("\\`*_[]<>|!&~#$")
"""Characters :func:`_md` escapes in copied text: those that start Markdown or HTML inside a
line (a copied text never starts a line)."""
MAX_RUN_SECONDS = 3600.0
"""Simulated seconds: a recorded run stops there unless ``--seconds`` says otherwise, and a
replay re-simulates no further unless ``--max-seconds`` says so (an hour is some 200 MB of
replay frames; the lab's longest task takes minutes)."""


class LoadedRun(NamedTuple):
    """What a replay needs: ``replay(*load_run(DIR))``."""

    config: SimConfig
    seed: int
    events: list[Event]


def _finite(value: Any) -> Any:
    """JSON-ready data: a float that is not finite becomes ``"nan"``, ``"inf"`` or ``"-inf"``
    (as in events.jsonl), in lists and dictionaries too."""
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    return value


def _write_json(path: Path, data: dict[str, Any]) -> None:
    write_text(path, json.dumps(_finite(data), indent=2, allow_nan=False) + "\n")


def prepare_folder(folder: str | Path) -> Path:
    """Make the folder (and its parents) for a new run; OSError if that fails, FileExistsError
    if it already holds a recorded run (which a new one would overwrite), UnsafeOutput if one
    of a run's file names there holds a link or no regular file (it would be written
    through)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if os.path.lexists(folder / MANIFEST):
        raise FileExistsError(
            f"{folder} already holds a recorded run; record into a new folder, or delete it"
        )
    for name in (MANIFEST, EVENTS, TRACE, SCANS, REPORT_JSON, REPORT_MD):
        check_target(folder / name)
    return folder


# ----------------------------------------------------------------------------- manifest


def sensor_ids(config: SimConfig) -> list[str]:
    """The trace's sensor columns, in configuration order: each sensor's id, and for a kind
    with several readings (an IMU's axes) its id with each reading's suffix (``i0-1``)."""
    columns = []
    for spec in config.devices:
        if spec.group == "sensors":
            kind = config.kinds.get(spec.kind)
            columns += [spec.id + suffix for suffix in (kind.readings if kind else ("",))]
    return columns


def config_to_manifest(config: SimConfig) -> dict[str, Any]:
    """The whole resolved configuration as plain data, and where it came from."""
    source = Path(config.source)
    is_file = source.is_file()
    return {
        "source": config.source,
        "path": str(source.resolve()) if is_file else None,
        "base_dir": str(source.resolve().parent if is_file else Path.cwd()),
        "original": source.suffix == ".py",
        "origin": config.origin,
        "warnings": [issue.render(config.source) for issue in config.warnings],
        "settings": config.settings.model_dump(mode="json"),
        "devices": [
            {
                "id": spec.id,
                "group": spec.group,
                "kind": spec.kind,
                "params": spec.params.model_dump(mode="json"),
            }
            for spec in config.devices
        ],
    }


def recorded_plugins(data: dict[str, Any]) -> list[str]:
    """The plug-ins a manifest's configuration names (its ``config`` part)."""
    settings = data.get("settings")
    plugins = settings.get("plugins") if isinstance(settings, dict) else None
    if plugins is None:
        return []
    if not isinstance(plugins, list) or not all(isinstance(p, str) for p in plugins):
        raise ValueError(f"config.settings.plugins is {plugins!r}, not a list of names")
    return list(plugins)


CODE_KINDS = frozenset({"simmer_device"})
"""Built-in device kinds that import a file their configuration names (the original SimMeR's
device classes, :mod:`simmer.compat.template`): in a run folder that file is code, as a plug-in
is, and is imported only with ``trust``."""
MAX_CODE_NAMED = 3
"""Pieces of code an :class:`~simmer.errors.UntrustedRun` names (then how many more), so that a
manifest listing thousands of devices still gets one line."""
MAX_NAME_CHARS = 60
"""Characters of a name read from a run folder that a message shows."""
MAX_SOURCE_CHARS = 4096
"""Characters of a manifest's ``config.source`` (the configuration's path) kept: its last ones,
as no path is longer. A 300,000-character one took 134 s to draw in a plot's title, and a
replay refusing the configuration printed all 10,000,000 of another."""


def recorded_source(text: str) -> str:
    """A manifest's ``config.source`` as SimMeR shows it: its last :data:`MAX_SOURCE_CHARS`
    characters, any that is not printable (a newline, a control character) as its escape."""
    text = text[-MAX_SOURCE_CHARS:]
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in text)


def shown_name(text: str) -> str:
    """A name read from a run folder, for a one-line message: as it is if printable and short,
    else its first :data:`MAX_NAME_CHARS` characters quoted with escapes (no newline, no
    control or bidirectional character reaches the terminal)."""
    if text.isprintable() and len(text) <= MAX_NAME_CHARS:
        return text
    return repr(text[:MAX_NAME_CHARS]) + ("..." if len(text) > MAX_NAME_CHARS else "")


def _device_tables(devices: list[Any]) -> dict[str, dict[str, Any]]:
    """A manifest's ``config.devices`` as the configuration's device tables, by group (ValueError
    for an entry that is not a recorded device)."""
    tables: dict[str, dict[str, Any]] = {group: {} for group in DEVICE_GROUPS}
    for device in devices:
        if not (
            isinstance(device, dict)
            and device.get("group") in DEVICE_GROUPS
            and isinstance(device.get("id"), str)
            and isinstance(device.get("params"), dict)
        ):
            raise ValueError(f"config.devices: {device!r:.80} is not a recorded device")
        tables[device["group"]][device["id"]] = device["params"]
    return tables


def recorded_code(
    plugins: Sequence[str], tables: dict[str, dict[str, Any]], *, own_plugins: bool
) -> list[str]:
    """The code re-simulating a configuration would run, in words: its ``plugins`` (unless the
    caller names its own), each device whose kind imports a file it names
    (:data:`CODE_KINDS`), and, unless the caller names plug-ins, each device of a kind SimMeR
    does not build in (only a plug-in or an installed package defines it); [] if it is data."""
    code = (
        [f"plug-ins ({', '.join(map(shown_name, plugins))})"] if plugins and not own_plugins else []
    )
    for group, table in tables.items():
        for device_id, params in table.items():
            kind = params.get("type", DEFAULT_KIND.get(group))
            if not isinstance(kind, str):
                continue  # not a kind: validation says so
            if kind in CODE_KINDS:
                module = params.get("module")
                file = Path(module).name if isinstance(module, str) else "?"
                code.append(f"device {shown_name(device_id)}'s class file ({shown_name(file)})")
            elif kind not in BUILTIN_KINDS and not own_plugins:
                code.append(
                    f"device {shown_name(device_id)} of kind {shown_name(kind)}, which only a "
                    "plug-in or an installed package defines"
                )
    if len(code) > MAX_CODE_NAMED:
        code[MAX_CODE_NAMED:] = [f"and {len(code) - MAX_CODE_NAMED:,} more"]
    return code


def config_from_manifest(
    data: dict[str, Any], *, trust: bool = False, plugins: Sequence[str | Path] | None = None
) -> SimConfig:
    """Validate a manifest's configuration again (ConfigError if it no longer validates,
    e.g. a plug-in file is gone): the same settings and devices as the recorded run's.

    A run folder is data: the code its configuration names (:func:`recorded_code`: plug-ins,
    a device class's file) is imported (run) only with ``trust``; ``plugins`` (files or module
    names of the caller's choosing, relative to the working directory) are imported in place
    of the plug-ins it names. Otherwise a configuration naming code is a
    :class:`~simmer.errors.UntrustedRun`, and nothing is imported."""
    if not isinstance(data.get("settings"), dict) or not isinstance(data.get("devices"), list):
        raise ValueError("its config has no settings table and devices list")
    named = recorded_plugins(data)
    tables = _device_tables(data["devices"])
    raw = dict(data["settings"])
    if plugins is not None:
        raw["plugins"] = [str(Path(p).resolve()) if _is_file(p) else str(p) for p in plugins]
    code = recorded_code(named, tables, own_plugins=plugins is not None)
    if code and not trust:
        raise UntrustedRun(code, plugins=bool(named))
    for group, table in tables.items():
        if not isinstance(raw.setdefault(group, {}), dict):
            raise ValueError(f"config.settings.{group} is not a table of devices")
        raw[group].update(table)
    config = config_from_dict(
        raw,
        recorded_source(str(data["source"])),
        Path(data["base_dir"]),
        original=bool(data["original"]),
    )
    return replace(config, origin=str(data.get("origin", "")))


def _is_file(entry: str | Path) -> bool:
    """Whether a plug-in entry is a file (else an installed module's name), as
    :func:`simmer.config.validate` tells them apart."""
    text = str(entry)
    return text.endswith(".py") or "/" in text or "\\" in text


def library_versions() -> dict[str, str]:
    """Versions of the libraries a run's numbers could depend on."""
    found = {}
    for name in ("numpy", "numba"):
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = "not installed"
    return found


def manifest(sim: Simulation, options: RunOptions | None, started: datetime) -> dict[str, Any]:
    """What a run folder says about its run before it starts (``options``: how it is served;
    None: a simulation Python code steps itself, with no clock)."""
    sensors = sensor_ids(sim.config)
    return {
        "format": FORMAT,
        "simmer_version": simmer.__version__,
        "started": started.isoformat(timespec="seconds"),
        "seed": sim.seed,
        "scenario": sim.scenario.as_dict(),
        "clock": options and options.clock,
        "speed": options and options.speed,
        "link_delay": options and options.link_delay,
        "program": options and options.program,
        "window": bool(options and options.window),
        "argv": sys.argv,
        "platform": {
            "python": platform.python_version(),
            "implementation": platform.python_implementation(),
            "os": platform.platform(),
            "machine": platform.machine(),
            **library_versions(),
        },
        "trace": {"rate": TRACE_RATE, "columns": trace_columns(sensors)},
        "config": config_to_manifest(sim.config),
    }


def read_json(path: Path) -> dict[str, Any]:
    """A JSON object SimMeR wrote (manifest.json, report.json), read at most
    :data:`MAX_JSON_BYTES`; ValueError naming the file if it is not one."""
    text = read_at_most(
        path, MAX_JSON_BYTES, "MAX_JSON_BYTES", "more than SimMeR writes: not a run's file"
    )
    data = parse_json(text, str(path), MAX_JSON_BYTES, "MAX_JSON_BYTES")
    if not isinstance(data, dict):
        raise ValueError(f"{path} holds {type(data).__name__}, not a JSON object")
    return data


def read_manifest(folder: str | Path) -> dict[str, Any]:
    """A run folder's manifest (ValueError naming the file if it is not one, or is from a
    newer SimMeR's layout)."""
    path = Path(folder) / MANIFEST
    data = read_json(path)
    layout = data.get("format", 0)
    if not isinstance(layout, int) or isinstance(layout, bool) or layout < 0:
        raise ValueError(f"{path}: format {layout!r} is not a run folder's layout number")
    if layout > FORMAT:
        raise ValueError(
            f"{path} is in layout {layout}, from a newer SimMeR "
            f"({data.get('simmer_version')!s:.40}) than this one ({simmer.__version__}, layout "
            f"{FORMAT}); update SimMeR to read it"
        )
    return data


def load_run(
    folder: str | Path,
    *,
    trust: bool = False,
    plugins: Sequence[str | Path] | None = None,
    max_seconds: float = MAX_RUN_SECONDS,
) -> LoadedRun:
    """A recorded run's configuration (validated again from the manifest), seed and events.

    Plug-ins the run was recorded with are imported only with ``trust`` (or ``plugins`` in
    their place: :func:`config_from_manifest`). ValueError naming the file if the manifest
    is not a run's; :class:`~simmer.errors.RunFolderError` (a ValueError) if its events
    cannot be read or go beyond ``max_seconds`` of simulated time (a replay would step that
    far: :func:`simmer.record.reader.read_events`)."""
    data = read_manifest(folder)
    where = Path(folder) / MANIFEST
    try:
        config = config_from_manifest(data["config"], trust=trust, plugins=plugins)
    except UntrustedRun as exc:
        raise UntrustedRun(exc.code, str(where), plugins=exc.names_plugins) from None
    except (TypeError, ValueError, AttributeError) as exc:  # a ConfigError is a SimmerError
        raise ValueError(f"{where}: not a run's manifest: {exc}") from None
    seed = data["seed"]
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**128:
        raise ValueError(f"{where}: seed {seed!r} is not a noise seed")
    path = Path(folder) / EVENTS
    max_steps = int(max_seconds * config.settings.frame_rate)
    return LoadedRun(config, seed, read_events(path, max_steps=max_steps))


def start_pose(config: SimConfig, seed: int) -> Pose:
    """Where a configuration's robot starts with this seed (a project's start may be drawn)."""
    settings = config.settings
    if settings.scenario.start == "config":
        return Pose(*settings.robot_start_position, wrap_degrees(settings.robot_start_rotation))
    return Simulation(config, seed=seed).scenario.start


def retrace(folder: str | Path, path: str | Path, scans: str | Path | None = None) -> Replayed:
    """Replay a recorded run and write its trace to ``path`` (and its LiDARs' scans to
    ``scans``, if given and it has a LiDAR): to compare them with the recorded ``trace.csv``
    and ``scans.csv``, or to write ones that ``kill -9`` cut short."""
    config, seed, events = load_run(folder)
    writer = TraceWriter(path, sensor_ids(config), config.settings.frame_rate)
    writer.begin(0.0, 0, start_pose(config, seed))
    sim = Simulation(config, seed=seed)
    scan_writer = ScanWriter(scans, sim) if scans is not None and lidar_ids(sim) else None
    for observer in (writer, scan_writer):
        if observer is not None:
            sim.add_observer(observer)
    try:
        return feed(sim, events)
    finally:
        writer.close()
        if scan_writer is not None:
            scan_writer.close()


# ----------------------------------------------------------------------------- report


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f} s"


def _numbers(value: Any, count: int) -> list[float] | None:
    """``count`` finite numbers from a list read back from a run folder, else None."""
    if not isinstance(value, list) or len(value) != count:
        return None
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        return None
    numbers = [float(v) for v in value]
    return numbers if all(math.isfinite(v) for v in numbers) else None


def _time(value: Any) -> str:
    """A milestone's time as report.md writes it: ``12.50 s``, or ``no``."""
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return f"{value:.2f} s"
    return "no"


def project_lines(outcome: dict[str, Any], scenario: Any) -> list[str]:
    """report.md's project section: the scenario, each milestone with its time, the score
    (whatever of it the run folder holds in the expected form)."""
    from simmer.world.outcome import MILESTONE_WORDS

    lines = ["## Project", ""]
    if isinstance(scenario, dict):
        start, block = _numbers(scenario.get("start"), 3), _numbers(scenario.get("block"), 2)
        target = scenario.get("target")
        if start is not None and block is not None and isinstance(target, str | None):
            lines += [
                f"Started at [{start[0]:g}, {start[1]:g}] heading {start[2]:g} deg; the block "
                f"at [{block[0]:.2f}, {block[1]:.2f}]; target zone {_md(target)}.",
                "",
            ]
    lines += ["| Milestone | Simulated time |", "| --- | --- |"]
    for name, words in MILESTONE_WORDS.items():
        lines.append(f"| {words[0].upper() + words[1:]} | {_time(outcome.get(f'{name}_at'))} |")
    wrong = outcome.get("wrong_zone")
    if isinstance(wrong, str) and not outcome.get("delivered"):
        at = _time(outcome.get("wrong_zone_at"))
        lines.append(f"| Put it down in another drop-off zone | {_md(wrong)} at {at} |")
    score = outcome.get("score")
    if isinstance(score, int | float) and not isinstance(score, bool):
        lines += ["", f"**Score: {score:g}** (the rubric is in the manifest).", ""]
    return lines


def _localization_rows(outcome: dict[str, Any]) -> list[str]:
    """The table's row for the program's reported poses, if it reported any."""
    count = outcome.get("estimates")
    if not isinstance(count, int) or isinstance(count, bool) or count <= 0:
        return []
    when = outcome.get("localized_at")
    said = f"at {_seconds(when)}" if isinstance(when, int | float) else "no"
    return [f"| Localized (within 3 in and 15 deg to the end; {count} estimates) | {said} |"]


def _link_rows(outcome: dict[str, Any]) -> list[str]:
    """The link model's row of report.md (none when it was off)."""
    if "link_bytes" not in outcome:
        return []
    return [
        f"| The link (messages, bytes delayed, seconds on it) | "
        f"{_md(outcome['link_messages'])}, {_md(outcome['link_bytes'])}, "
        f"{outcome['link_seconds']:.2f} s |",
        f"| The link: bytes lost, bytes corrupted, dropouts (messages lost in them) | "
        f"{_md(outcome['link_lost'])}, {_md(outcome['link_corrupted'])}, "
        f"{_md(outcome['link_dropouts'])} ({_md(outcome['link_in_dropout'])}) |",
    ]


def write_report_md(folder: str | Path) -> Path:
    """Write ``report.md`` from the folder's report.json and manifest: the outcome in plain
    words, and ``path.png`` and ``sensors.png`` if they are there (``simmer plot`` calls this
    again after drawing them)."""
    folder = Path(folder)
    info = read_manifest(folder)
    report = read_json(folder / REPORT_JSON)
    try:
        lines = _report_lines(folder, info, report)
    except (KeyError, TypeError, ValueError) as exc:
        what = f"no {exc}" if isinstance(exc, KeyError) else str(exc)
        raise ValueError(
            f"{folder / REPORT_JSON} (or {MANIFEST}) is not what SimMeR writes: {what}"
        ) from None
    path = folder / REPORT_MD
    write_text(path, "\n".join(lines))
    return path


def _printable(value: Any) -> str:
    """Text read from a run folder as one line: at most :data:`MAX_REPORT_CHARS` characters,
    every character that is not printable (a newline, a control or bidirectional one) written
    as its escape (``\\n``, ``\\u202e``)."""
    text = str(value)
    if len(text) > MAX_REPORT_CHARS:
        text = text[:MAX_REPORT_CHARS] + "..."
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in text)


def _md(value: Any) -> str:
    """Text read from a run folder for report.md's prose and tables: :func:`_printable`, with
    every character Markdown or HTML would read as markup escaped by a backslash (so ``<b>``,
    ``[a](b)``, ``|`` and ``**`` stay text)."""
    return "".join(f"\\{c}" if c in MARKDOWN_SPECIAL else c for c in _printable(value))


def _code(value: Any) -> str:
    """Text read from a run folder as a Markdown code span (:func:`_printable`), fenced by more
    backticks than it holds in a row, so it cannot end the span early."""
    text = _printable(value)
    fence = "`" * (max((len(run) for run in re.findall("`+", text)), default=0) + 1)
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{fence}{pad}{text}{pad}{fence}"


def _report_lines(folder: Path, info: dict[str, Any], report: dict[str, Any]) -> list[str]:
    """report.md's lines (KeyError, TypeError or ValueError if a file is malformed)."""
    outcome = report["outcome"]
    x, y, heading = outcome["final_pose"]
    reached = f"yes, at {_seconds(outcome['reached_at'])}" if outcome["reached"] else "no"
    first = outcome["first_collision"]
    later = f" (first at {_seconds(first)})" if first is not None else ""
    collisions = f"{_md(outcome['collisions'])}{later}"
    ended = _md(RunEnd.words_for(report["ended_by"]))
    if report["program_status"] is not None:
        ended += f" with status {_md(report['program_status'])}"
    program = f", program {_code(info['program'])}" if info["program"] else ""
    clock = f", {_md(info['clock'])} clock" if info["clock"] else ""
    started = datetime.fromisoformat(info["started"]).strftime("%Y-%m-%d %H:%M")
    lines = [
        f"# SimMeR run: {_md(folder.name)}",
        "",
        f"Recorded on {started} with SimMeR {_md(info['simmer_version'])}: configuration "
        f"{_code(info['config']['source'])}, noise seed {_md(info['seed'])}{clock}{program}. "
        "Times are simulated seconds; distances are inches.",
        "",
        "| | |",
        "| --- | --- |",
        f"| Reached the block | {reached} |",
        f"| Task 2 time (first motion to the block) | {_seconds(outcome['task2_time'])} |",
        f"| Collisions | {collisions}; {_md(outcome['blocked_steps'])} steps blocked |",
        f"| Path length | {outcome['path_length']:.1f} in |",
        f"| Messages, commands | {_md(outcome['messages'])}, {_md(outcome['commands'])} |",
        f"| Busy replies (a drive still moving), NaN replies | "
        f"{_md(outcome.get('busy_replies', 0))}, {_md(outcome['nan_replies'])} |",
        f"| Final pose | x {x:.2f} in, y {y:.2f} in, heading {heading:.1f} deg |",
        *_localization_rows(outcome),
        *_link_rows(outcome),
        f"| Length of the run | {report['duration']:.2f} s ({_md(report['steps'])} steps), "
        f"{report['wall_seconds']:.1f} s of wall-clock time |",
        f"| How it ended | {ended} |",
        "",
        "Reached the block: the robot's outline came within 1 in of the block's. The Task 2 "
        "time runs from the robot's first motion until then. A busy reply is a drive command "
        "refused while a drive was moving; a NaN reply, a command that could not be carried "
        "out (malformed, or an unknown device).",
        "",
    ]
    if "score" in outcome:
        lines += project_lines(outcome, info.get("scenario"))
    if report.get("recording_stopped"):
        stopped = _md(report["recording_stopped"])
        lines += [f"**{stopped}**; the files hold the run until then.", ""]
    if report["resets"]:
        count = report["resets"]
        times = "once" if count == 1 else f"{_md(count)} times"
        lines += [f"The simulation was reset {times}; the figures count from the last reset.", ""]
    lines += [
        f"Files: `{MANIFEST}` (configuration, seed, versions), `{EVENTS}` (every command and "
        f"reply, in order), `{TRACE}` (pose and sensor readings, {TRACE_RATE:g} rows a "
        f"second), `{REPORT_JSON}` (these figures).",
        "",
    ]
    plots = [(name, alt) for name, alt in PLOTS if (folder / name).exists()]
    if plots:
        lines += ["## Plots", "", *(f"![{alt}]({name})\n" for name, alt in plots)]
    else:
        lines += [
            f"{_code(f'simmer plot {folder}')} adds the path and the sensors' readings here.",
            "",
        ]
    return lines


# ----------------------------------------------------------------------------- recorder


class RunRecorder:
    """Record ``sim`` into ``folder`` (see the module doc) until :meth:`close`; or use it as a
    context manager::

        with RunRecorder(sim, "runs/task1"):
            sim.command("w0-12")
            sim.run_until_idle()

    ``options``: how the run is served, for the manifest (None: Python code steps the
    simulation itself). ``outcome``: the run's :class:`~simmer.world.outcome.Outcome` if it
    has one already (otherwise the recorder attaches its own, until :meth:`close`).
    ``max_bytes``: what events.jsonl and trace.csv may hold together (default: the options'
    ``record_limit``). If they reach it, or the disk fills, the
    recording stops (each file at its last whole line) and the run goes on: :attr:`stopped`
    says why and ``on_stop`` is called with "the recording in DIR stopped: ...". Raises
    ValueError if ``sim`` has already stepped (a recording starts at the first step, or it
    could not be replayed), and FileExistsError or OSError as :func:`prepare_folder` does.
    """

    def __init__(
        self,
        sim: Simulation,
        folder: str | Path,
        options: RunOptions | None = None,
        outcome: Outcome | None = None,
        *,
        max_bytes: int | None = None,
        on_stop: Callable[[str], None] | None = None,
    ) -> None:
        if sim.steps != 0:
            raise ValueError(
                f"record a run from its start: the simulation is at step {sim.steps} "
                "(start recording before stepping it, or after sim.reset())"
            )
        self.sim = sim
        self.folder = prepare_folder(folder)
        self.options = options
        if max_bytes is None:
            max_bytes = MAX_RECORDING_BYTES if options is None else options.record_limit
        self._own_outcome = outcome is None
        self.outcome = Outcome.attach(sim) if outcome is None else outcome
        self._wall_start = time.monotonic()
        self.started = datetime.now().astimezone()
        self.stopped: str | None = None
        """Why the recording stopped before the run ended ("the recording in DIR stopped:
        disk full"), or None."""
        self._on_stop = on_stop
        _write_json(self.folder / MANIFEST, manifest(sim, options, self.started))
        budget = RecordingBudget(max_bytes)
        self.events = EventLog(self.folder / EVENTS, budget, self._stop)
        settings = sim.config.settings
        self.trace = TraceWriter(
            self.folder / TRACE, sensor_ids(sim.config), settings.frame_rate, budget, self._stop
        )
        self.trace.begin(sim.time, sim.steps, sim.robot.pose)
        self.scans = ScanWriter(self.folder / SCANS, sim) if lidar_ids(sim) else None
        """The LiDARs' scans (:mod:`simmer.record.scans`), if the robot has a LiDAR."""
        sim.add_observer(self.events)
        sim.add_observer(self.trace)
        if self.scans is not None:
            sim.add_observer(self.scans)
        self.closed = False

    def _stop(self, reason: str) -> None:
        """One file could not be written: stop both, so that they end together."""
        if self.stopped is not None:
            return
        self.stopped = f"the recording in {self.folder} stopped: {reason}"
        self.events.stop(reason)
        self.trace.stop(reason)
        if self._on_stop is not None:
            self._on_stop(self.stopped)

    def close(self, ended_by: RunEnd = RunEnd.CLOSED, program_status: int | None = None) -> None:
        """Stop recording: close events.jsonl and trace.csv and write the report (again:
        nothing). ``ended_by`` says how the run ended."""
        if self.closed:
            return
        self.closed = True
        sim = self.sim
        sim.remove_observer(self.events)
        sim.remove_observer(self.trace)
        if self.scans is not None:
            sim.remove_observer(self.scans)
            self.scans.close()
        if self._own_outcome:
            sim.remove_observer(self.outcome)
        self.events.close()
        self.trace.close()
        report = {
            "simmer_version": simmer.__version__,
            "config": sim.config.source,
            "seed": sim.seed,
            "clock": self.options and self.options.clock,
            "duration": sim.time,
            "steps": sim.steps,
            "wall_seconds": time.monotonic() - self._wall_start,
            "ended_by": ended_by,
            "program_status": program_status,
            "resets": self.trace.resets,
            "events": self.events.written,
            "trace_rows": self.trace.rows,
            **({} if self.scans is None else {"scans": self.scans.scans}),
            **({} if self.scans is None else {"scans_stopped": self.scans.stopped}),
            "recording_stopped": self.stopped,
            "outcome": self.outcome.report().as_dict(),
        }
        try:
            _write_json(self.folder / REPORT_JSON, report)
            write_report_md(self.folder)
        except OSError as exc:  # a full disk: the events and trace say what there is
            self._stop(stop_reason(exc))
            for name in (REPORT_JSON, REPORT_MD):  # not half a report: none
                with suppress(OSError):
                    (self.folder / name).unlink(missing_ok=True)

    def __enter__(self) -> RunRecorder:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        _exc: BaseException | None,
        _tb: TracebackType | None,
    ) -> None:
        if kind is None:
            self.close()
        else:
            self.close(RunEnd.QUIT if issubclass(kind, KeyboardInterrupt) else RunEnd.ERROR)
