"""A sweep's results: ``results.csv`` (one row per run, appended as runs finish, put in the
sweep's order at the end), the kept runs' folders under ``runs/``, and ``summary.md`` (success
rate per setting with 95% Wilson score intervals, pictures, and a gallery of the failing runs
grouped by how they failed).
"""

from __future__ import annotations

import csv
import math
import shutil
import statistics
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from simmer.ending import RunEnd
from simmer.record.safefile import check_folder, check_target, replacing, write_bytes, write_text
from simmer.sweep.runs import RunResult, RunSpec
from simmer.sweep.spec import SweepSpec

if TYPE_CHECKING:
    from simmer.config import SimConfig
from simmer.sweep.success import (
    OUTCOME_FIELDS,
    PROJECT_FIELDS,
    failure_kind,
    failures,
    flat_outcome,
)

__all__ = [
    "RUNS",
    "ResultsFile",
    "SettingSummary",
    "flat_outcome",
    "header",
    "keep_files",
    "outcome_cells",
    "read_rows",
    "row",
    "summarize",
    "wilson_interval",
    "write_summary",
]

Z95 = 1.959963984540054
"""The standard normal quantile for a two-sided 95% interval."""
TAIL_COLUMNS = ("status", "exit_status", "wall_time", "run", "folder", "detail")
RUNS = "runs"
"""The folder (in the sweep's) of the kept runs' folders."""
MAX_RESULTS_BYTES = 256 * 1024 * 1024
"""Largest results.csv read back by ``--resume``: the most runs a sweep has, with long
output tails, take some 100 MB."""
GALLERY = 8
"""Failing runs shown per kind of failure in summary.md (results.csv lists them all)."""
FRAME_WIDTH = 300
"""Pixels the gallery shows a frame across."""
Pictures = Callable[
    [Path, SweepSpec, Sequence[Mapping[str, str]], Sequence["SettingSummary"]],
    list[tuple[str, str]],
]
"""Draws a summary's pictures into its folder; returns each file's name and caption."""


def wilson_interval(successes: int, trials: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval for a success rate (95% by default): unlike p ± z·se it
    stays within [0, 1] and means something at 0 or n successes, which small sweeps have."""
    if trials <= 0:
        return 0.0, 1.0
    p = successes / trials
    z2 = z * z
    centre = (p + z2 / (2 * trials)) / (1 + z2 / trials)
    half = z * math.sqrt(p * (1 - p) / trials + z2 / (4 * trials * trials)) / (1 + z2 / trials)
    low = 0.0 if successes == 0 else max(0.0, centre - half)  # exactly, not 1e-17 off
    high = 1.0 if successes == trials else min(1.0, centre + half)
    return low, high


def header(spec: SweepSpec) -> list[str]:
    """results.csv's columns: the swept keys, seed, success and how the run failed, the
    outcome, then the run's own (status, exit status, wall time, key, folder, output)."""
    project = PROJECT_FIELDS if spec.project else ()
    return [*spec.columns, "seed", "success", "failure", *OUTCOME_FIELDS, *project, *TAIL_COLUMNS]


def _cell(value: Any) -> str:
    """A value as written: floats exactly (repr), None as empty."""
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return str(value)


def outcome_cells(result: RunResult, project: bool = False) -> list[str]:
    """A run's outcome as results.csv has it (:data:`OUTCOME_FIELDS`' columns, and with
    ``project`` :data:`PROJECT_FIELDS`')."""
    fields = flat_outcome(result.outcome)
    names = (*OUTCOME_FIELDS, *PROJECT_FIELDS) if project else OUTCOME_FIELDS
    return [_cell(fields.get(name)) for name in names]


def row(run: RunSpec, result: RunResult, folder: str = "", project: bool = False) -> list[str]:
    """One run's row of results.csv (``folder``: its kept folder, relative to the sweep's;
    ``project``: with the project's columns)."""
    return [
        *map(_cell, run.setting),
        str(run.seed),
        str(result.success),
        failure_kind(result.status, flat_outcome(result.outcome), result.success, project),
        *outcome_cells(result, project),
        result.status,
        _cell(result.exit_status),
        f"{result.wall_time:.3f}",
        result.key,
        folder,
        " | ".join(result.detail.splitlines()[-8:]),
    ]


def _is_kept_folder(cell: str) -> bool:
    """Whether a results row's ``folder`` cell is empty or a folder under ``runs/``."""
    parts = cell.split("/")
    return not cell or (
        len(parts) == 2
        and parts[0] == RUNS
        and parts[1] not in ("", ".", "..")
        and "\\" not in cell
    )


def keep_files(folder: Path, name: str, files: Mapping[str, bytes]) -> str:
    """Write a run's files into ``folder``/runs/``name`` (replacing what a stopped sweep left
    there), its report.md written again for its place; its path relative to ``folder``."""
    target = folder / RUNS / name
    check_folder(folder / RUNS, missing_ok=True)  # not a link: what is under it is removed
    check_folder(target, missing_ok=True)
    if target.exists():
        shutil.rmtree(target)
    target.mkdir(parents=True)
    for file, data in files.items():
        write_bytes(target / file, data)
    if "report.json" in files and "manifest.json" in files:
        from simmer.record.runfolder import write_report_md

        write_report_md(target)  # named after its folder here, not the worker's scratch one
    return f"{RUNS}/{name}"


class ResultsFile:
    """``results.csv``, appended to and flushed as each run finishes, so a stopped sweep keeps
    every finished run and ``--resume`` can skip them."""

    def __init__(self, path: Path, columns: Sequence[str], *, resume: bool) -> None:
        self.path = path
        self.columns = list(columns)
        self.done: dict[str, list[str]] = {}
        if path.exists() and not resume:
            raise FileExistsError(
                f"{path} exists: --resume to finish that sweep, or choose another output folder"
            )
        if path.exists():
            self.done = self._read()
        path.parent.mkdir(parents=True, exist_ok=True)
        check_target(path, run_folder=False)  # appended to: not through a link
        self._file: IO[str] = path.open("a", encoding="utf-8", newline="")
        self._writer = csv.writer(self._file)
        if not self.done and path.stat().st_size == 0:
            self._writer.writerow(self.columns)
            self._file.flush()

    def _read(self) -> dict[str, list[str]]:
        """The finished runs' rows by key (ValueError naming the file if it is not a results
        table). A row whose folder is not one of ``runs/`` is not taken as done: it would
        point the filming of failures elsewhere."""
        size = self.path.stat().st_size
        if size > MAX_RESULTS_BYTES:
            raise ValueError(
                f"{self.path} is {size:,} bytes, more than the results of a sweep's runs "
                f"({MAX_RESULTS_BYTES:,}): not a results table"
            )
        try:
            with self.path.open(encoding="utf-8", newline="") as file:
                rows = list(csv.reader(file))
        except (csv.Error, UnicodeError) as exc:
            raise ValueError(f"{self.path} is not a results table: {exc}") from None
        if not rows:
            return {}
        if rows[0] != self.columns:
            raise ValueError(f"{self.path} holds another sweep's results (other columns)")
        at, kept = self.columns.index("run"), self.columns.index("folder")
        return {
            r[at]: r for r in rows[1:] if len(r) == len(self.columns) and _is_kept_folder(r[kept])
        }

    def add(self, cells: list[str]) -> None:
        """Append one run's row and flush it to disk."""
        self._writer.writerow(cells)
        self._file.flush()
        self.done[cells[self.columns.index("run")]] = cells

    def close(self, order: Iterable[str] | None = None) -> None:
        """Close the file; with ``order`` (every run's key, in the sweep's order), rewrite it
        in that order, so the same sweep gives the same table however its runs finished."""
        self._file.close()
        if order is None:
            return
        with (
            replacing(self.path, run_folder=False) as temporary,
            temporary.open("w", encoding="utf-8", newline="") as file,
        ):
            writer = csv.writer(file)
            writer.writerow(self.columns)
            writer.writerows(self.done[key] for key in order if key in self.done)


@dataclass(frozen=True)
class SettingSummary:
    """The runs of one setting (one combination of the grid's values)."""

    setting: tuple[str, ...]
    runs: int
    successes: int
    statuses: dict[str, int]
    failures: dict[str, int]

    @property
    def interval(self) -> tuple[float, float]:
        """95% Wilson score interval of the success rate."""
        return wilson_interval(self.successes, self.runs)


def _counts(values: Iterable[str]) -> dict[str, int]:
    counts: dict[str, int] = {}
    for value in values:
        counts[value] = counts.get(value, 0) + 1
    return counts


def summarize(columns: Sequence[str], rows: Sequence[Mapping[str, str]]) -> list[SettingSummary]:
    """Success counts per setting, in the order settings first appear."""
    groups: dict[tuple[str, ...], list[Mapping[str, str]]] = {}
    for cells in rows:
        groups.setdefault(tuple(cells[c] for c in columns), []).append(cells)
    return [
        SettingSummary(
            setting,
            len(members),
            sum(cells["success"] == "True" for cells in members),
            _counts(cells["status"] for cells in members),
            _counts(cells["failure"] for cells in members if cells["failure"]),
        )
        for setting, members in groups.items()
    ]


def read_rows(path: Path) -> list[dict[str, str]]:
    """results.csv as dictionaries."""
    with path.open(encoding="utf-8", newline="") as file:
        return list(csv.DictReader(file))


def write_summary(
    folder: Path,
    spec: SweepSpec,
    source: str,
    pictures: Pictures | None = None,
    remarks: Sequence[str] = (),
) -> Path:
    """Write ``summary.md`` from ``results.csv`` in ``folder``: with ``pictures``, a function
    drawing them into ``folder``; ``remarks``, lines to add at the end."""
    rows = read_rows(folder / "results.csv")
    columns = list(spec.setting_columns)
    summaries = summarize(columns, rows)
    total = sum(s.successes for s in summaries)
    low, high = wilson_interval(total, len(rows))
    lines = [
        f"# Sweep {source}" if source else "# Sweep",
        "",
        f"{len(rows)} runs: {spec.kind} `{spec.controller}`, seeds {_seeds(spec.seeds)}"
        f"{_sampled(spec)}, success when `{spec.success}`.",
        "",
        f"Overall success {total}/{len(rows)} = {_rate(total, len(rows))} "
        f"(95% Wilson interval {low:.3f} to {high:.3f}).",
        "",
        *_fixed_noise(spec),
        *_localized(rows),
        *(_project(rows) if spec.project else []),
        "| "
        + " | ".join(
            [
                *(f"`{c}`" for c in columns),
                "runs",
                "successes",
                "rate",
                "95% interval",
                *(PROJECT_CELLS if spec.project else ()),
                "failures",
                "statuses",
            ]
        )
        + " |",
        "|" + "---|" * (len(columns) + 6 + (len(PROJECT_CELLS) if spec.project else 0)),
    ]
    for s in summaries:
        a, b = s.interval
        members = [r for r in rows if tuple(r[c] for c in columns) == s.setting]
        cells = [
            *s.setting,
            str(s.runs),
            str(s.successes),
            _rate(s.successes, s.runs),
            f"{a:.3f} to {b:.3f}",
            *(_project_cells(members) if spec.project else ()),
            _listed(s.failures, failures(spec.project)) or "-",
            _listed(s.statuses),
        ]
        lines.append("| " + " | ".join(_escape(c) for c in cells) + " |")
    if pictures is not None:
        drawn = pictures(folder, spec, rows, summaries)
        lines += ["", "## Pictures", ""]
        for name, caption in drawn:
            lines += [f"![{caption}]({name})", "", f"*{caption}*", ""]
        lines.pop()
    lines += _gallery(folder, spec, rows)
    if remarks:
        lines += ["", "## Notes", "", *(f"- {remark}" for remark in remarks)]
    path = folder / "summary.md"
    write_text(path, "\n".join(lines) + "\n", run_folder=False)
    return path


def fixed_noise(config: SimConfig, swept: Sequence[str]) -> list[str]:
    """The base configuration's noise that no key of the sweep changes, each as a dotted key
    and its value (``drives.w0.bias.rotation = 0.2``): every run has it, whatever the grid
    says, so a row of zeros is not noise-free when this is not empty."""
    from pydantic import BaseModel

    fixed = []
    for device in config.devices:
        for name in ("error", "bias"):
            value = getattr(device.params, name, 0.0)
            parts = value.model_dump() if isinstance(value, BaseModel) else {"": value}
            for axis, number in parts.items():
                key = f"{device.group}.{device.id}.{name}" + (f".{axis}" if axis else "")
                if number != 0 and not any(key.startswith(k) or k.startswith(key) for k in swept):
                    fixed.append(f"`{key} = {number:g}`")
    settings = config.settings
    if settings.rand_bias and any(settings.bias_strength) and "rand_bias" not in swept:
        fixed.append(f"`rand_bias = true` (strength `{list(settings.bias_strength)}`)")
    return fixed


def _fixed_noise(spec: SweepSpec) -> list[str]:
    """A line saying the base configuration's fixed noise (or that it has none)."""
    from simmer.config import load_config
    from simmer.errors import ConfigError

    try:
        config = load_config(spec.configs[0])
    except (ConfigError, OSError):  # the runs said so, each in its row
        return []
    swept = [key for key, _ in spec.grid] + [key for key, _ in spec.sample]
    fixed = fixed_noise(config, swept)
    if not fixed:
        return ["The base configuration has no other noise: every error and bias the sweep does "
                "not set is 0.", ""]  # fmt: skip
    return [
        f"In every run, whatever the setting, the base configuration ({spec.configs[0].name}) "
        f"adds this noise the sweep does not change: {', '.join(fixed)}.",
        "",
    ]


def _numbers(rows: Sequence[Mapping[str, str]], column: str) -> list[float]:
    """A column's values in the runs that have one."""
    return [float(r[column]) for r in rows if r.get(column)]


def score_figures(scores: Sequence[float]) -> str:
    """Scores as the summary says them: mean ± standard deviation, median and range."""
    if not scores:
        return "-"
    spread = statistics.stdev(scores) if len(scores) > 1 else 0.0
    return (
        f"mean {statistics.fmean(scores):.1f} ± {spread:.1f} (median "
        f"{statistics.median(scores):g}, from {min(scores):g} to {max(scores):g})"
    )


def delivery_figures(times: Sequence[float]) -> str:
    """Delivery times as the summary says them: median, mean and range, in seconds."""
    if not times:
        return "none delivered"
    return (
        f"median {statistics.median(times):.1f} s (mean {statistics.fmean(times):.1f} s, "
        f"from {min(times):.1f} to {max(times):.1f} s)"
    )


def _project(rows: Sequence[Mapping[str, str]]) -> list[str]:
    """A project sweep's lines: score, delivery rate and time, and how far the runs got."""
    scores = _numbers(rows, "score")
    delivered = sum(r.get("delivered") == "True" for r in rows)
    low, high = wilson_interval(delivered, len(rows))
    reached = ", ".join(
        f"{name} {sum(r.get(column) == 'True' for r in rows)}"
        for column, name in (
            ("entered_loading", "entered the loading zone"),
            ("picked_up", "picked up the block"),
            ("left_loading", "left the loading zone holding it"),
            ("delivered", "delivered it to the target"),
        )
    )
    wrong = sum(bool(r.get("wrong_zone")) for r in rows)
    return [
        f"Score (the rubric's points, of the {_plural(len(scores), 'run')} with one): "
        f"{score_figures(scores)}.",
        "",
        f"Delivered to the target in {delivered}/{len(rows)} = {_rate(delivered, len(rows))} "
        f"(95% Wilson interval {low:.3f} to {high:.3f}); delivery time (simulated seconds "
        f"from the start) {delivery_figures(_numbers(rows, 'delivered_at'))}.",
        "",
        f"How far the {len(rows)} runs got: {reached}"
        + (f"; {wrong} delivered it to another zone." if wrong else "."),
        "",
    ]


PROJECT_CELLS = ("mean score (sd)", "delivered", "median delivery time")
"""A project sweep's columns of the per-setting table, after the success rate."""


def _project_cells(rows: Sequence[Mapping[str, str]]) -> list[str]:
    """A setting's :data:`PROJECT_CELLS`."""
    scores = _numbers(rows, "score")
    spread = statistics.stdev(scores) if len(scores) > 1 else 0.0
    times = _numbers(rows, "delivered_at")
    delivered = sum(r.get("delivered") == "True" for r in rows)
    return [
        f"{statistics.fmean(scores):.1f} ({spread:.1f})" if scores else "-",
        f"{delivered}/{len(rows)}",
        f"{statistics.median(times):.1f} s" if times else "-",
    ]


def _milestones(r: Mapping[str, str]) -> list[str]:
    """A project run's facts for the gallery: its milestones with their times, its score."""
    met = [
        f"{name} at {float(r[column + '_at']):.1f} s"
        for column, name in (
            ("entered_loading", "entered the loading zone"),
            ("picked_up", "picked up"),
            ("left_loading", "left the loading zone"),
            ("delivered", "delivered"),
        )
        if r.get(column) == "True" and r.get(column + "_at")
    ]
    if r.get("wrong_zone"):
        met.append(f"delivered to {r['wrong_zone']}, not {r.get('target') or 'its target'}")
    if r.get("picked_up") != "True":
        met.append("never picked up the block")
    score = f"score {float(r['score']):g}" if r.get("score") else "no score"
    return [*met, score]


def _localized(rows: Sequence[Mapping[str, str]]) -> list[str]:
    """A line on time to localize, if any run's program reported its pose."""
    reported = [r for r in rows if r.get("estimates")]
    if not reported:
        return []
    times = sorted(float(r["localized_at"]) for r in reported if r.get("localized_at"))
    low, high = wilson_interval(len(times), len(reported))
    said = (
        f"; time to localize median {statistics.median(times):.2f} s "
        f"(from {times[0]:.2f} to {times[-1]:.2f} s)"
        if times
        else ""
    )
    return [
        f"Localized (the reported pose within 3 in and 15 deg to the end) in "
        f"{len(times)}/{len(reported)} runs that reported one (95% Wilson interval {low:.3f} "
        f"to {high:.3f}){said}.",
        "",
    ]


def _gallery(folder: Path, spec: SweepSpec, rows: Sequence[Mapping[str, str]]) -> list[str]:
    """The failing runs, by how they failed: setting, seed, first and last frame, links to
    the video and the run's folder, and what happened (at most :data:`GALLERY` of each)."""
    failed = [r for r in rows if r["failure"]]
    if not failed:
        return []
    kinds = _counts(r["failure"] for r in failed)
    if spec.keep == "nothing":
        kept = 'No run\'s folder was kept (keep = "nothing").'
    else:
        kept = (
            f'Their folders are in `{RUNS}/` (keep = "{spec.keep}"): manifest, events, trace, '
            "report, and the first and last frame"
        )
        if spec.videos == 1:
            kept += "; the first failure in the sweep's order has a video."
        elif spec.videos:
            kept += f"; the first {spec.videos} failures in the sweep's order have a video."
        else:
            kept += "."
    lines = [
        "",
        "## Failing runs",
        "",
        f"{_plural(len(failed), 'run')} failed: {_listed(kinds, failures(spec.project))} "
        "(the `failure` "
        f"column of results.csv). {kept}",
    ]
    for kind, meaning in failures(spec.project).items():
        members = [r for r in failed if r["failure"] == kind]
        if not members:
            continue
        lines += [
            "",
            f"### {kind.replace('-', ' ').capitalize()}: {meaning} ({len(members)})",
            "",
            "| setting | seed | first frame | last frame | files | what happened |",
            "|---|---|---|---|---|---|",
        ]
        for r in _chosen(folder, spec, members):
            cells = [
                _setting_text(spec, r),
                r["seed"],
                _frame(folder, r, "first.png"),
                _frame(folder, r, "last.png"),
                _links(folder, r),
                _happened(r),
            ]
            lines.append("| " + " | ".join(_escape(c) for c in cells) + " |")
        if len(members) > GALLERY:
            lines += [
                "",
                f"And {len(members) - GALLERY} more: results.csv's rows with failure = {kind}.",
            ]
    return lines


def _chosen(
    folder: Path, spec: SweepSpec, members: Sequence[Mapping[str, str]]
) -> list[Mapping[str, str]]:
    """At most :data:`GALLERY` of a kind of failure, in the sweep's order: those with a video
    first, then one from each setting in turn (the first failure of each, then the second...),
    so the gallery shows as many settings as it can."""
    turn: dict[tuple[str, ...], int] = {}
    ranked = []
    for index, r in enumerate(members):
        setting = tuple(r[c] for c in spec.setting_columns)
        turn[setting] = turn.get(setting, -1) + 1
        filmed = bool(r["folder"]) and (folder / r["folder"] / "video.mp4").exists()
        ranked.append((not filmed, turn[setting], index))
    picked = sorted(index for *_, index in sorted(ranked)[:GALLERY])
    return [members[index] for index in picked]


def _setting_text(spec: SweepSpec, r: Mapping[str, str]) -> str:
    sampled = {key for key, _ in spec.sample}
    parts = [
        f"sample {r[c]}" if c == "sample" else f"`{c}` = {r[c]}"
        for c in spec.columns
        if c not in sampled
    ]
    shown = [f"`{c}` = {_short(r[c])}" for c in spec.columns if c in sampled]
    text = ", ".join(parts)
    return f"{text} ({', '.join(shown)})" if shown else text or "-"


def _short(value: str) -> str:
    """A drawn number with 4 significant digits (the table has it exactly)."""
    try:
        return f"{float(value):.4g}"
    except ValueError:
        return value


def _frame(folder: Path, r: Mapping[str, str], name: str) -> str:
    path = f"{r['folder']}/{name}"
    if not r["folder"] or not (folder / path).exists():
        return "-"
    return f'<img src="{path}" width="{FRAME_WIDTH}" alt="{name[:-4]} frame">'


def _links(folder: Path, r: Mapping[str, str]) -> str:
    if not r["folder"]:
        return "-"
    video = f"{r['folder']}/video.mp4"
    links = [f"[video]({video})"] if (folder / video).exists() else []
    return ", ".join([*links, f"[run folder]({r['folder']}/)"])


def _happened(r: Mapping[str, str]) -> str:
    """A few words on the run: how it ended and the outcome's telling figures."""
    status = r["status"]
    if not r["time"]:
        return f"{status}: {r['detail'][-160:]}" if r["detail"] else status
    ended = RunEnd(status).label if status in set(RunEnd) else status
    if status == RunEnd.ERROR and r["exit_status"]:
        ended += f" (exit status {r['exit_status']})"
    facts = [f"{ended} at {float(r['time']):.1f} s"]
    if r["collisions"] != "0":
        collisions = _plural(int(r["collisions"]), "collision")
        facts.append(f"{collisions}, the first at {float(r['first_collision']):.1f} s")
    if "score" in r:  # a project run: its milestones and score, not Lab 1's Task 2 time
        facts += _milestones(r)
    elif r["reached"] == "True":
        facts.append(f"Task 2 time {float(r['task2_time']):.1f} s")
    facts.append(f"ended at ({float(r['final_x']):.1f}, {float(r['final_y']):.1f}) in")
    if status == RunEnd.ERROR and r["detail"]:
        facts.append(r["detail"][-160:])
    return "; ".join(facts)


def _plural(count: int, noun: str) -> str:
    return f"{count} {noun}" if count == 1 else f"{count} {noun}s"


def _escape(text: str) -> str:
    """A table cell's text (a ``|`` would end the cell)."""
    return text.replace("|", "\\|").replace("\n", " ")


def _listed(counts: Mapping[str, int], order: Iterable[str] | None = None) -> str:
    names = [n for n in order if n in counts] if order is not None else sorted(counts)
    return ", ".join(f"{name} {counts[name]}" for name in names)


def _sampled(spec: SweepSpec) -> str:
    if not spec.sample:
        return ""
    keys = ", ".join(f"`{key}` ~ {distribution}" for key, distribution in spec.sample)
    grid = " for each setting" if spec.setting_columns else ""
    return f", {spec.sample_count} random draws{grid} (sample_seed {spec.sample_seed}) of {keys}"


def _rate(successes: int, runs: int) -> str:
    return f"{successes / runs:.0%}" if runs else "-"


def _seeds(seeds: Sequence[int]) -> str:
    if list(seeds) == list(range(len(seeds))):
        return f"0 to {len(seeds) - 1}"
    return ", ".join(map(str, seeds))
