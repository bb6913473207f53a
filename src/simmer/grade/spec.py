"""The grading file: the teams' programs, the scenarios every one of them runs, the rubric and
the limits (``simmer grade GRADING.toml``).

```toml
config = "project.toml"        # the robot and maze, unless a team names its own
answer = "{target}"            # typed at each program's prompt ({target}: the run's zone)
seconds = 300                  # simulated seconds per run
wall_seconds = 60              # wall seconds per run
success = "delivered and collisions == 0"
rank = "score"                 # "score" (the project's, a project configuration's default)
                               # or "success" (the success rate)
videos = 1                     # videos of each team's first failures

[scenarios]                    # every combination (the seed changing fastest) ...
seeds = [1, 2]
"scenario.target" = "all"      # any configuration key, as in a sweep's [grid]

# [[scenario]]                 # ... or a list the TA writes, one table a scenario
# seed = 3
# "scenario.start" = "0,0,90"

[limits]                       # each program's box (docs/grading.md says what is enforced)
cpu_seconds = 60
memory_mb = 1024
file_mb = 16
processes = 32
open_files = 256
landlock = true                # Linux: files, ports and signals confined
network = true                 # Linux: a network of its own, the simulator's ports only

[[team]]
name = "Team 1"
folder = "teams/team1"         # relative to the grading file
program = "python3 -u robot.py"
config = "robot.toml"          # optional: the team's own robot, relative to its folder
```
"""

from __future__ import annotations

import itertools
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from simmer.errors import SweepError
from simmer.lockstep.box import BoxLimits, check_folder
from simmer.sweep.runs import RunSpec
from simmer.sweep.spec import (
    DEFAULT_WALL_SECONDS,
    LIMITS,
    _checked_success,
    _count,
    _did_you_mean,
    _dotted,
    _every_scenario,
    _grid,
    _is_project,
    _limit,
    _read_text,
    _seeds,
)
from simmer.sweep.success import DEFAULT_SUCCESS

__all__ = ["GradeSpec", "Scenario", "Team", "grade_from_dict", "load_grading"]

Rank = Literal["score", "success"]
KNOWN_KEYS = frozenset(
    {
        "config",
        "answer",
        "seconds",
        "wall_seconds",
        "success",
        "rank",
        "videos",
        "scenarios",
        "scenario",
        "limits",
        "team",
    }
)
TEAM_KEYS = frozenset({"name", "folder", "program", "config"})
LIMIT_KEYS = (
    "cpu_seconds",
    "memory_mb",
    "file_mb",
    "processes",
    "open_files",
    "landlock",
    "network",
)
MAX_TEAMS = 500
"""Teams in a grading file (a course of 400 students in teams of 4 has 100)."""
MAX_SCENARIOS = 1_000
"""Scenarios in a grading file: with :data:`MAX_TEAMS` teams, 500,000 runs at most."""
MAX_TEAM_NAME = 40
"""Characters of a team's name (it heads a row of the leaderboard and names its folders)."""
MAX_LIMIT = {"cpu_seconds": 86_400, "memory_mb": 65_536, "file_mb": 65_536, "processes": 4_096}
MAX_LIMIT["open_files"] = 65_536
"""Largest value of each ``[limits]`` key."""


@dataclass(frozen=True)
class Team:
    """One team: its name, its folder (copied into a box for each run), its command line and
    the configuration it runs on."""

    name: str
    folder: Path
    program: str
    config: Path

    @property
    def slug(self) -> str:
        """The team's name as a file name (letters, digits, ``.``, ``_``, ``-``)."""
        return re.sub(r"[^A-Za-z0-9._-]", "-", self.name).strip(".") or "team"


@dataclass(frozen=True)
class Scenario:
    """One scenario: a seed and the configuration keys it sets, and its name."""

    seed: int
    overrides: tuple[tuple[str, Any], ...]

    @property
    def name(self) -> str:
        """``target=B1_seed1``: each key's last name and value, then the seed."""
        parts = [f"{key.rsplit('.', 1)[-1]}={value}" for key, value in self.overrides]
        return re.sub(r"[^A-Za-z0-9._=+-]", "-", "_".join([*parts, f"seed{self.seed}"]))


@dataclass(frozen=True)
class GradeSpec:
    """A parsed grading file; :meth:`runs` lists every team's run of every scenario."""

    folder: Path
    config: Path
    teams: tuple[Team, ...]
    scenarios: tuple[Scenario, ...]
    keys: tuple[str, ...]
    """The scenarios' configuration keys (the results' columns after ``team``)."""
    seconds: float | None
    wall_seconds: float
    success: str
    rank: Rank
    limits: BoxLimits
    answer: str | None = None
    videos: int = 0
    project: bool = False

    @property
    def columns(self) -> tuple[str, ...]:
        """results.csv's columns before the seed: the team, then the scenario's keys."""
        return ("team", *self.keys)

    def only(self, folder: Path) -> GradeSpec:
        """The grading of the one team whose folder is ``folder`` (a student's ``--only .``);
        a folder no team has becomes a team named after it, running the first team's command
        line (SweepError if there is no team at all)."""
        wanted = folder.resolve()
        mine = tuple(team for team in self.teams if team.folder == wanted)
        if not mine:
            first = self.teams[0]
            config = self.config if first.config == self.config else wanted / first.config.name
            mine = (Team(wanted.name or "mine", wanted, first.program, config),)
        return GradeSpec(**{**self.__dict__, "teams": mine})

    def runs(self) -> list[RunSpec]:
        """Every run: each team (in the file's order), each scenario."""
        return [
            RunSpec(
                config=str(team.config),
                overrides=scenario.overrides,
                seed=scenario.seed,
                kind="program",
                controller=team.program,
                folder=str(team.folder),
                seconds=self.seconds,
                wall_seconds=self.wall_seconds,
                setting=(team.name, *(value for _, value in scenario.overrides)),
                success=self.success,
                keep="all",
                answer=self.answer,
                team=team.name,
                box=self.limits,
            )
            for team in self.teams
            for scenario in self.scenarios
        ]

    def folder_names(self) -> dict[str, str]:
        """Each run's folder under ``runs/``, by run key: ``TEAM_SCENARIO``."""
        pairs = [(team, scenario) for team in self.teams for scenario in self.scenarios]
        return {
            run.key(): f"{team.slug}_{scenario.name}"
            for (team, scenario), run in zip(pairs, self.runs(), strict=True)
        }


def load_grading(path: Path) -> GradeSpec:
    """Read and check a grading file (SweepError: one line naming the file, the key and the
    fix)."""
    path = Path(path)
    try:
        data = tomllib.loads(_read_text(path))
    except OSError as exc:
        raise SweepError(f"cannot read {path}: {exc.strerror or exc}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SweepError(f"{path}: not valid TOML: {exc}") from None
    try:
        return grade_from_dict(data, path.resolve().parent)
    except SweepError as exc:
        raise SweepError(f"{path}: {exc}") from None


def grade_from_dict(data: Mapping[str, Any], folder: Path) -> GradeSpec:
    """A grading from the grading file's data; relative paths are from ``folder``."""
    unknown = sorted(set(data) - KNOWN_KEYS)
    if unknown:
        hints = "".join(_did_you_mean(key, KNOWN_KEYS) for key in unknown)
        raise SweepError(
            f"unknown key(s) {', '.join(unknown)}{hints}; known: {', '.join(sorted(KNOWN_KEYS))}"
        )
    config = _file(data.get("config"), folder, "config")
    project = _is_project(config)
    teams = _teams(data.get("team"), folder, config)
    keys, scenarios = _scenarios(data, config)
    rank = data.get("rank", "score" if project else "success")
    if rank not in ("score", "success"):
        raise SweepError(f'rank: "score" or "success", not {rank!r}')
    if rank == "score" and not project:
        raise SweepError(
            'rank = "score" needs the course project\'s configuration (a robot with a '
            'gripper); rank = "success" ranks by the success rate'
        )
    answer = data.get("answer")
    if answer is not None and (not isinstance(answer, str) or len(answer) > 4096):
        raise SweepError(
            f'answer: text such as "{{target}}" (at most 4,096 characters), not {answer!r}'
        )
    return GradeSpec(
        folder=folder,
        config=config,
        teams=teams,
        scenarios=scenarios,
        keys=keys,
        seconds=_limit(data, "seconds", None),
        wall_seconds=_limit(data, "wall_seconds", DEFAULT_WALL_SECONDS) or DEFAULT_WALL_SECONDS,
        success=_checked_success(data.get("success", DEFAULT_SUCCESS)),
        rank=rank,
        limits=_limits(data.get("limits", {})),
        answer=answer,
        videos=_count(data, "videos", 0),
        project=project,
    )


def _file(value: Any, folder: Path, where: str) -> Path:
    if not isinstance(value, str) or not value:
        raise SweepError(
            f"{where}: a configuration file (.toml or config.py), relative to {folder}"
        )
    path = (folder / value).resolve()
    if not path.is_file():
        raise SweepError(f"{where}: no such file {path}")
    return path


def _teams(value: Any, folder: Path, config: Path) -> tuple[Team, ...]:
    example = (
        '[[team]] tables: name = "Team 1", folder = "teams/team1", program = "python3 robot.py"'
    )
    if not isinstance(value, list) or not value or not all(isinstance(t, dict) for t in value):
        raise SweepError(f"team: one or more {example}")
    if len(value) > MAX_TEAMS:
        raise SweepError(f"team: {len(value):,} teams; at most {MAX_TEAMS} (MAX_TEAMS; {LIMITS})")
    teams = []
    for number, entry in enumerate(value, 1):
        where = f"team {number}"
        unknown = sorted(set(entry) - TEAM_KEYS)
        if unknown:
            hints = "".join(_did_you_mean(key, TEAM_KEYS) for key in unknown)
            raise SweepError(
                f"{where}: unknown key(s) {', '.join(unknown)}{hints}; known: name, folder, "
                "program, config"
            )
        name = entry.get("name")
        if not isinstance(name, str) or not name.strip() or len(name) > MAX_TEAM_NAME:
            raise SweepError(
                f"{where}: name, 1 to {MAX_TEAM_NAME} characters (MAX_TEAM_NAME), not {name!r:.60}"
            )
        if not name.isprintable():
            raise SweepError(f"{where}: name {name!r:.60} has characters that cannot be shown")
        where = f"team {name!r}"
        home = entry.get("folder")
        if not isinstance(home, str) or not (folder / home).is_dir():
            raise SweepError(
                f"{where}: folder, the team's folder relative to {folder}, not {home!r}"
            )
        home_path = (folder / home).resolve()
        try:
            check_folder(home_path)
        except ValueError as exc:
            raise SweepError(f"{where}: {exc}") from None
        program = entry.get("program")
        if not isinstance(program, str) or not program.strip():
            raise SweepError(f'{where}: program, its command line ("python3 -u robot.py")')
        own = _file(entry["config"], home_path, f"{where} config") if "config" in entry else config
        teams.append(Team(name.strip(), home_path, program, own))
    for team in teams:
        inside = next(
            (o for o in teams if o.folder != team.folder and o.folder.is_relative_to(team.folder)),
            None,
        )
        if inside is not None:
            raise SweepError(
                f"team {team.name!r}: folder {team.folder} holds team {inside.name!r}'s folder "
                "(it would be copied into the first team's box, to be read): give each team a "
                'folder of its own, side by side ("teams/team1", "teams/team2")'
            )
    names = [team.name for team in teams]
    slugs = [team.slug for team in teams]
    if len(set(names)) < len(names) or len(set(slugs)) < len(slugs):
        raise SweepError("team: each team's name once (names that differ only in punctuation too)")
    return tuple(teams)


def _scenarios(
    data: Mapping[str, Any], config: Path
) -> tuple[tuple[str, ...], tuple[Scenario, ...]]:
    """The scenario keys and the scenarios, from ``[scenarios]`` (a product) or
    ``[[scenario]]`` (a list)."""
    if "scenarios" in data and "scenario" in data:
        raise SweepError("[scenarios] (every combination) or [[scenario]] (a list): one of them")
    if "scenario" in data:
        return _listed(data["scenario"])
    table = data.get("scenarios", {})
    if not isinstance(table, dict):
        raise SweepError('[scenarios]: seeds = [1, 2] and keys such as "scenario.target" = "all"')
    table = dict(table)
    seeds = _seeds(table.pop("seeds", 1))
    grid = _grid(_every_scenario(table, config))
    keys = tuple(key for key, _ in grid)
    scenarios: list[Scenario] = []
    for values in itertools.product(*(values for _, values in grid)):
        for seed in seeds:
            scenarios.append(Scenario(seed, tuple(zip(keys, values, strict=True))))
            if len(scenarios) > MAX_SCENARIOS:
                raise SweepError(
                    f"[scenarios]: more than {MAX_SCENARIOS:,} scenarios (MAX_SCENARIOS; {LIMITS})"
                )
    return keys, tuple(scenarios)


def _listed(value: Any) -> tuple[tuple[str, ...], tuple[Scenario, ...]]:
    if not isinstance(value, list) or not value or not all(isinstance(s, dict) for s in value):
        raise SweepError("[[scenario]]: one table per scenario, with seed = N and keys")
    if len(value) > MAX_SCENARIOS:
        raise SweepError(
            f"[[scenario]]: {len(value):,}; at most {MAX_SCENARIOS:,} (MAX_SCENARIOS; {LIMITS})"
        )
    entries = []
    keys: list[str] = []
    for number, given in enumerate(value, 1):
        table = dict(given)
        seed = table.pop("seed", 0)
        if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
            raise SweepError(f"[[scenario]] {number}: seed, a whole number 0 or more, not {seed!r}")
        pairs = _dotted(table, lambda _table: False)
        keys += [key for key, _ in pairs if key not in keys]
        entries.append((seed, dict(pairs)))
    scenarios = []
    for seed, named in entries:
        missing = [key for key in keys if key not in named]
        if missing:
            raise SweepError(
                f"[[scenario]] with seed {seed}: sets no {', '.join(missing)}; every scenario "
                "sets the same keys (write the value of the configuration where it is the same)"
            )
        scenarios.append(Scenario(seed, tuple((key, named[key]) for key in keys)))
    if len({(s.seed, repr(s.overrides)) for s in scenarios}) < len(scenarios):
        raise SweepError("[[scenario]]: a scenario is listed twice")
    return tuple(keys), tuple(scenarios)


def _limits(value: Any) -> BoxLimits:
    if not isinstance(value, dict):
        raise SweepError("[limits]: cpu_seconds, memory_mb, file_mb, processes, open_files")
    unknown = sorted(set(value) - set(LIMIT_KEYS))
    if unknown:
        hints = "".join(_did_you_mean(key, LIMIT_KEYS) for key in unknown)
        raise SweepError(
            f"[limits]: unknown key(s) {', '.join(unknown)}{hints}; known: {', '.join(LIMIT_KEYS)}"
        )
    given: dict[str, Any] = {}
    for key, number in value.items():
        if key in ("landlock", "network"):
            if not isinstance(number, bool):
                raise SweepError(f"[limits] {key}: true or false, not {number!r}")
            given[key] = number
            continue
        top = MAX_LIMIT[key]
        if isinstance(number, bool) or not isinstance(number, int | float) or not 0 < number <= top:
            raise SweepError(
                f"[limits] {key}: a number more than 0 and at most {top:,} (MAX_LIMIT; "
                f"{LIMITS}), not {number!r:.40}"
            )
        given[key] = float(number) if key == "cpu_seconds" else int(number)
    return BoxLimits(**given)
