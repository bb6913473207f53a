"""What a grading writes from its results: the leaderboard (CSV, Markdown, HTML), a report
per team and the violation log. Read from results.csv alone, so a resumed grading writes the
same files as one that ran in one go.
"""

from __future__ import annotations

import csv
import html
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from simmer.grade.spec import GradeSpec, Team
from simmer.record.safefile import write_text

__all__ = ["VIOLATIONS", "Standing", "standings", "violations", "write_board"]

VIOLATIONS = {
    "never-connected": "the program sent the simulator nothing",
    "crash": "the program exited with an error",
    "timeout": "the wall-clock limit stopped it (it hung, or looped)",
    "time-limit": "the simulated-time limit stopped it",
    "collision": "the robot hit a wall or the block",
    "protocol": "malformed commands (NaN replies other than busy ones)",
    "cpu-limit": "it used more CPU time than [limits] cpu_seconds",
    "memory-limit": "it asked for more memory than [limits] memory_mb",
    "file-size-limit": "it wrote a file larger than [limits] file_mb",
    "process-limit": "it started more processes than [limits] processes",
    "open-files-limit": "it opened more files than [limits] open_files",
    "refused-access": "it tried to read or write outside its box",
    "network-refused": "it tried a connection other than to the simulator",
    "message-limit": "it sent a message over MAX_MESSAGE_BYTES (64 KiB, a line without end: "
    "its connection closed) or MAX_COMMANDS (1,000 commands): refused whole",
}
"""The kinds of violation the log records, and what each means."""
MILESTONES = ("entered_loading_at", "picked_up_at", "left_loading_at", "delivered_at")
SIGNALS = {-24: "cpu-limit", -25: "file-size-limit", -9: "", -15: ""}
"""Exit statuses (killed by a signal) that name a limit: SIGXCPU, SIGXFSZ."""
PATTERNS = (
    ("MemoryError", "memory-limit"),
    ("Cannot allocate memory", "memory-limit"),
    ("File too large", "file-size-limit"),
    ("Resource temporarily unavailable", "process-limit"),
    ("Too many open files", "open-files-limit"),
    ("Permission denied", "refused-access"),
    ("Operation not permitted", "refused-access"),
)
"""Words of a failed program's last output that name what stopped it."""


def violations(cells: Mapping[str, str]) -> list[str]:
    """A run's violations (keys of :data:`VIOLATIONS`) from its results.csv row."""
    found = []
    status, detail = cells["status"], cells["detail"]
    if not cells["messages"] or cells["messages"] == "0":
        found.append("never-connected")
    if status in ("error", "crashed"):
        found.append("crash")
        exit_status = int(cells["exit_status"]) if cells["exit_status"].lstrip("-").isdigit() else 0
        named = SIGNALS.get(exit_status) or next(
            (kind for words, kind in PATTERNS if words in detail), ""
        )
        if ("Permission denied" in detail and "connect" in detail) or (
            "Network is unreachable" in detail  # no network but the simulator's (its own)
        ):
            named = "network-refused"
        if named:
            found.append(named)
    if status == "timeout":
        found.append("timeout")
    if status == "seconds":
        found.append("time-limit")
    if cells["collisions"] not in ("", "0"):
        found.append("collision")
    if cells["nan_replies"] not in ("", "0"):
        found.append("protocol")
    if cells.get("over_limit", "") not in ("", "0"):
        found.append("message-limit")
    return found


@dataclass(frozen=True)
class Standing:
    """One team's line of the leaderboard."""

    team: Team
    runs: int
    successes: int
    score: float | None
    """Mean score over its runs (a project grading), else None."""
    time: float | None
    """Mean time to success (delivered or reached) over its successful runs."""
    collisions: int
    violations: int
    crashes: int

    @property
    def rate(self) -> float:
        """Success rate."""
        return self.successes / self.runs if self.runs else 0.0


def _number(cell: str) -> float:
    return float(cell) if cell else 0.0


def standings(spec: GradeSpec, rows: Sequence[Mapping[str, str]]) -> list[Standing]:
    """Every team's standing, best first: by mean score (``rank = "score"``) or success rate,
    then successes, then the mean time to success (less first), then collisions (fewer
    first), then the file's order."""
    done = "delivered_at" if spec.project else "reached_at"
    table = []
    for team in spec.teams:
        mine = [r for r in rows if r["team"] == team.name]
        wins = [r for r in mine if r["success"] == "True"]
        times = [float(r[done]) for r in wins if r.get(done)]
        table.append(
            Standing(
                team=team,
                runs=len(mine),
                successes=len(wins),
                score=sum(_number(r["score"]) for r in mine) / len(mine)
                if spec.project and mine
                else None,
                time=sum(times) / len(times) if times else None,
                collisions=sum(int(_number(r["collisions"])) for r in mine),
                violations=sum(len(violations(r)) for r in mine),
                crashes=sum("crash" in violations(r) for r in mine),
            )
        )
    order = {team.name: i for i, team in enumerate(spec.teams)}

    def key(s: Standing) -> tuple[float, ...]:
        first = -(s.score or 0.0) if spec.rank == "score" else -s.rate
        return (
            first,
            -s.successes,
            s.time if s.time is not None else math.inf,
            s.collisions,
            order[s.team.name],
        )

    return sorted(table, key=key)


def _shown(value: float | None, digits: int = 2) -> str:
    return "" if value is None else f"{value:.{digits}f}"


BOARD_COLUMNS = (
    "rank",
    "team",
    "score",
    "successes",
    "runs",
    "success_rate",
    "time",
    "collisions",
    "violations",
    "crashes",
)


def board_rows(spec: GradeSpec, table: Sequence[Standing]) -> list[list[str]]:
    """The leaderboard's rows (:data:`BOARD_COLUMNS`)."""
    return [
        [
            str(rank),
            s.team.name,
            _shown(s.score),
            str(s.successes),
            str(s.runs),
            f"{s.rate:.3f}",
            _shown(s.time),
            str(s.collisions),
            str(s.violations),
            str(s.crashes),
        ]
        for rank, s in enumerate(table, 1)
    ]


def write_board(
    folder: Path,
    spec: GradeSpec,
    rows: Sequence[Mapping[str, str]],
    source: str,
    thumbnails: Mapping[str, str],
    notes: Sequence[str] = (),
) -> list[Standing]:
    """Write leaderboard.csv, leaderboard.md, index.html, teams/TEAM.md and violations.csv
    into ``folder``; the standings. ``notes``: lines about the box put under the table."""
    table = standings(spec, rows)
    lines = board_rows(spec, table)
    _write_csv(folder / "leaderboard.csv", [list(BOARD_COLUMNS), *lines])
    header = "| " + " | ".join(BOARD_COLUMNS) + " |"
    rule = "|" + "---|" * len(BOARD_COLUMNS)
    body = ["| " + " | ".join(_md(cell) for cell in line) + " |" for line in lines]
    what = "mean score" if spec.rank == "score" else "success rate"
    write_text(
        folder / "leaderboard.md",
        "\n".join(
            [
                f"# Leaderboard: {_md(source)}",
                "",
                f"{len(spec.teams)} team(s), {len(spec.scenarios)} scenario(s) each; ranked by "
                f"{what}, then successes, then the mean time to success. Success: "
                f"`{spec.success}`.",
                "",
                header,
                rule,
                *body,
                "",
                *[f"Note: {_md(note)}\n" for note in notes],
            ]
        ),
    )
    (folder / "teams").mkdir(exist_ok=True)
    for standing in table:
        mine = [r for r in rows if r["team"] == standing.team.name]
        write_text(
            folder / "teams" / f"{standing.team.slug}.md", _team_report(spec, standing, mine)
        )
    log = [["team", "scenario", "seed", "violation", "meaning", "folder", "detail"]]
    log += [
        [
            r["team"],
            _scenario(spec, r),
            r["seed"],
            kind,
            VIOLATIONS[kind],
            r["folder"],
            r["detail"].split(" | ")[-1],
        ]
        for r in rows
        for kind in violations(r)
    ]
    _write_csv(folder / "violations.csv", log)
    write_text(folder / "index.html", _page(folder, spec, table, rows, source, thumbnails))
    return table


def _write_csv(path: Path, rows: Sequence[Sequence[str]]) -> None:
    text = io.StringIO()
    csv.writer(text).writerows(rows)
    write_text(path, text.getvalue(), run_folder=False)


def _scenario(spec: GradeSpec, r: Mapping[str, str]) -> str:
    return ", ".join(f"{key.rsplit('.', 1)[-1]} {r[key]}" for key in spec.keys) or "default"


def _md(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _team_report(spec: GradeSpec, s: Standing, rows: Sequence[Mapping[str, str]]) -> str:
    score = f", mean score {_shown(s.score)}" if s.score is not None else ""
    lines = [
        f"# {_md(s.team.name)}",
        "",
        f"{s.successes}/{s.runs} scenarios succeeded{score}; {s.collisions} collision(s), "
        f"{s.violations} violation(s). Program: `{s.team.program}`.",
        "",
    ]
    milestones = MILESTONES if spec.project else ("reached_at",)
    columns = ["scenario", "seed", "success", *milestones, "time", "collisions"]
    columns += ["score"] if spec.project else []
    columns += ["status", "violations"]
    lines += ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        cells = [
            _scenario(spec, r),
            r["seed"],
            r["success"],
            *(_short(r[m]) for m in milestones),
            _short(r["time"]),
            r["collisions"],
        ]
        cells += [r["score"]] if spec.project else []
        cells += [r["status"], ", ".join(violations(r))]
        lines.append("| " + " | ".join(_md(c) for c in cells) + " |")
    failed = [r for r in rows if r["detail"]]
    if failed:
        lines += ["", "## The program's last output lines where it failed", ""]
        for r in failed:
            lines += [
                f"**{_md(_scenario(spec, r))}, seed {r['seed']}** ({r['status']}):",
                "",
                "```text",
                *r["detail"].replace("```", "'''").split(" | "),
                "```",
                "",
            ]
    return "\n".join(lines) + "\n"


def _short(cell: str) -> str:
    try:
        return f"{float(cell):.2f}" if cell else ""
    except ValueError:
        return cell


def _page(
    folder: Path,
    spec: GradeSpec,
    table: Sequence[Standing],
    rows: Sequence[Mapping[str, str]],
    source: str,
    thumbnails: Mapping[str, str],
) -> str:
    e = html.escape
    out = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>Leaderboard: {e(source)}</title>",
        "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:4px 8px;text-align:right;vertical-align:middle}"
        "td.name{text-align:left}img{width:160px}tr.bad{background:#fdecea}"
        "code{font-size:90%}</style></head><body>",
        f"<h1>Leaderboard: {e(source)}</h1>",
        f"<p>{len(spec.teams)} team(s), {len(spec.scenarios)} scenario(s) each. Success: "
        f"<code>{e(spec.success)}</code>.</p>",
        "<table><tr><th>rank</th><th>team</th><th>run</th><th>score</th><th>successes</th>"
        "<th>mean time (s)</th><th>collisions</th><th>violations</th>"
        "<th>replay and video</th></tr>",
    ]
    for rank, s in enumerate(table, 1):
        mine = [r for r in rows if r["team"] == s.team.name]
        thumb = thumbnails.get(s.team.name)
        image = f'<img src="{e(thumb)}" alt="path of {e(s.team.name)}">' if thumb else ""
        kept = [r["folder"] for r in mine if r["folder"]]
        videos = [f"{run}/video.mp4" for run in kept if (folder / run / "video.mp4").is_file()]
        links = []
        if kept:
            links.append(f"<code>simmer replay {e(' '.join(kept[:4]))}</code>")
        links += [f'<a href="{e(v)}">video</a>' for v in videos]
        bad = ' class="bad"' if s.crashes or s.successes == 0 else ""
        out.append(
            f'<tr{bad}><td>{rank}</td><td class=name><a href="teams/{e(s.team.slug)}.md">'
            f"{e(s.team.name)}</a></td><td>{image}</td><td>{_shown(s.score)}</td>"
            f"<td>{s.successes}/{s.runs}</td><td>{_shown(s.time)}</td><td>{s.collisions}</td>"
            f"<td>{s.violations}</td><td class=name>{' '.join(links)}</td></tr>"
        )
    out += ["</table>", *_side_by_side(spec, table, rows)]
    out += [
        '<p><a href="violations.csv">Violation log</a> · <a href="results.csv">every run</a></p>',
        "</body></html>",
        "",
    ]
    return "\n".join(out)


SIDE_BY_SIDE_SCENARIOS = 5
"""Scenarios whose side-by-side commands the page lists (results.csv has every run)."""


def _side_by_side(
    spec: GradeSpec, table: Sequence[Standing], rows: Sequence[Mapping[str, str]]
) -> list[str]:
    """The page's commands that show the best teams' runs of a scenario side by side (in a
    window, and as a video), for the first :data:`SIDE_BY_SIDE_SCENARIOS` scenarios."""
    from simmer.view.compare import MAX_COMPARED

    e = html.escape
    best = [s.team.name for s in table][:MAX_COMPARED]
    lines = []
    for scenario in spec.scenarios[:SIDE_BY_SIDE_SCENARIOS]:
        values = {key: str(value) for key, value in scenario.overrides}
        runs = {
            r["team"]: r["folder"]
            for r in rows
            if r["folder"]
            and r["seed"] == str(scenario.seed)
            and all(r[key] == value for key, value in values.items())
        }
        folders = [runs[name] for name in best if name in runs]
        if len(folders) < 2:
            continue
        named = " ".join(folders)
        lines.append(
            f"<li>{e(scenario.name)}: <code>simmer replay {e(named)}</code> "
            f"· video: <code>simmer render {e(named)} -o compare-{e(scenario.name)}.mp4</code></li>"
        )
    if not lines:
        return []
    return [
        f"<h2>Side by side</h2><p>The best {len(best)} teams' runs of a scenario in one maze "
        "(one colour each, a red cross once a robot collides), from this folder:</p><ul>",
        *lines,
        "</ul>",
    ]
