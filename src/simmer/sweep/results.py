"""A sweep's results: ``results.csv`` (one row per run, appended as runs finish, put in the
sweep's order at the end) and ``summary.md`` (success rate per setting with 95% Wilson score
intervals, and pictures).
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from simmer.sweep.runs import RunResult, RunSpec
from simmer.sweep.spec import OUTCOME_FIELDS, SweepSpec

Z95 = 1.959963984540054
"""The standard normal quantile for a two-sided 95% interval."""
TAIL_COLUMNS = ("status", "exit_status", "wall_time", "run", "detail")


def wilson_interval(successes: int, trials: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval for a success rate (95% by default): unlike p ± z·se it
    stays within [0, 1] and means something at 0 or n successes, which small sweeps have."""
    if trials <= 0:
        return 0.0, 1.0
    p = successes / trials
    z2 = z * z
    centre = (p + z2 / (2 * trials)) / (1 + z2 / trials)
    half = z * math.sqrt(p * (1 - p) / trials + z2 / (4 * trials * trials)) / (1 + z2 / trials)
    return max(0.0, centre - half), min(1.0, centre + half)


def header(spec: SweepSpec) -> list[str]:
    """results.csv's columns: the swept keys, seed, success, the outcome, then the run's."""
    return [*spec.columns, "seed", "success", *OUTCOME_FIELDS, *TAIL_COLUMNS]


def flat_outcome(outcome: Mapping[str, Any] | None) -> dict[str, Any]:
    """An outcome's fields as the table has them (the final pose in three columns)."""
    if outcome is None:
        return {}
    fields = {k: v for k, v in outcome.items() if k != "final_pose"}
    fields["final_x"], fields["final_y"], fields["final_heading"] = outcome["final_pose"]
    return fields


def _cell(value: Any) -> str:
    """A value as written: floats exactly (repr), None as empty."""
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return str(value)


def row(run: RunSpec, result: RunResult, success: bool) -> list[str]:
    """One run's row of results.csv."""
    fields = flat_outcome(result.outcome)
    return [
        *map(_cell, run.setting),
        str(run.seed),
        str(success),
        *(_cell(fields.get(name)) for name in OUTCOME_FIELDS),
        result.status,
        _cell(result.exit_status),
        f"{result.wall_time:.3f}",
        result.key,
        " | ".join(result.detail.splitlines()[-8:]),
    ]


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
        self._file: IO[str] = path.open("a", encoding="utf-8", newline="")
        self._writer = csv.writer(self._file)
        if not self.done and path.stat().st_size == 0:
            self._writer.writerow(self.columns)
            self._file.flush()

    def _read(self) -> dict[str, list[str]]:
        with self.path.open(encoding="utf-8", newline="") as file:
            rows = list(csv.reader(file))
        if not rows:
            return {}
        if rows[0] != self.columns:
            raise ValueError(f"{self.path} holds another sweep's results (other columns)")
        at = self.columns.index("run")
        return {r[at]: r for r in rows[1:] if len(r) == len(self.columns)}

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
        temporary = self.path.with_suffix(".csv.tmp")
        with temporary.open("w", encoding="utf-8", newline="") as file:
            writer = csv.writer(file)
            writer.writerow(self.columns)
            writer.writerows(self.done[key] for key in order if key in self.done)
        os.replace(temporary, self.path)


@dataclass(frozen=True)
class SettingSummary:
    """The runs of one setting (one combination of the swept values)."""

    setting: tuple[str, ...]
    runs: int
    successes: int
    statuses: dict[str, int]

    @property
    def interval(self) -> tuple[float, float]:
        """95% Wilson score interval of the success rate."""
        return wilson_interval(self.successes, self.runs)


def summarize(columns: Sequence[str], rows: Sequence[Mapping[str, str]]) -> list[SettingSummary]:
    """Success counts per setting, in the order settings first appear."""
    groups: dict[tuple[str, ...], list[Mapping[str, str]]] = {}
    for cells in rows:
        groups.setdefault(tuple(cells[c] for c in columns), []).append(cells)
    summaries = []
    for setting, members in groups.items():
        statuses: dict[str, int] = {}
        for cells in members:
            statuses[cells["status"]] = statuses.get(cells["status"], 0) + 1
        successes = sum(cells["success"] == "True" for cells in members)
        summaries.append(SettingSummary(setting, len(members), successes, statuses))
    return summaries


def read_rows(path: Path) -> list[dict[str, str]]:
    """results.csv as dictionaries."""
    with path.open(encoding="utf-8", newline="") as file:
        return list(csv.DictReader(file))


def write_summary(
    folder: Path, spec: SweepSpec, source: str, pictures: Callable[..., list[str]] | None = None
) -> Path:
    """Write ``summary.md`` from ``results.csv`` in ``folder`` (with ``pictures``, a function
    drawing them into ``folder`` and returning their file names)."""
    rows = read_rows(folder / "results.csv")
    columns = list(spec.columns)
    summaries = summarize(columns, rows)
    total = sum(s.successes for s in summaries)
    low, high = wilson_interval(total, len(rows))
    lines = [
        f"# Sweep {source}" if source else "# Sweep",
        "",
        f"{len(rows)} runs: {spec.kind} `{spec.controller}`, seeds {_seeds(spec.seeds)}, "
        f"success when `{spec.success}`.",
        "",
        f"Overall success {total}/{len(rows)} = {_rate(total, len(rows))} "
        f"(95% Wilson interval {low:.3f} to {high:.3f}).",
        "",
        "| "
        + " | ".join(
            [*(f"`{c}`" for c in columns), "runs", "successes", "rate", "95% interval", "statuses"]
        )
        + " |",
        "|" + "---|" * (len(columns) + 5),
    ]
    for s in summaries:
        a, b = s.interval
        statuses = ", ".join(f"{k} {v}" for k, v in sorted(s.statuses.items()))
        cells = [
            *s.setting,
            str(s.runs),
            str(s.successes),
            _rate(s.successes, s.runs),
            f"{a:.3f} to {b:.3f}",
            statuses,
        ]
        lines.append("| " + " | ".join(cells) + " |")
    failed = [r for r in rows if r["status"] not in ("ok", "seconds")]
    if failed:
        lines += ["", "## Runs that did not finish", ""]
        lines += [
            f"- seed {r['seed']}"
            + "".join(f", `{c}` = {r[c]}" for c in columns)
            + f": **{r['status']}**"
            + (f": {r['detail'][-200:]}" if r["detail"] else "")
            for r in failed
        ]
    if pictures is not None:
        names = pictures(folder, spec, rows, summaries)
        lines += ["", "## Pictures", ""] + [f"![{name}]({name})" for name in names]
    path = folder / "summary.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _rate(successes: int, runs: int) -> str:
    return f"{successes / runs:.0%}" if runs else "-"


def _seeds(seeds: Sequence[int]) -> str:
    if list(seeds) == list(range(len(seeds))):
        return f"0 to {len(seeds) - 1}"
    return ", ".join(map(str, seeds))
