"""The sweep file: what to run (a configuration, a controller, seeds, a grid and a random sample
of overrides), the limits, what counts as success and what to keep.

```toml
config = "config.py"                 # or a list of files: then a swept column `config`
program = "python3 -u dead_reckoning.py"   # or: policy = "module:function"
seeds = 4                            # or a list: [1, 5, 9]
seconds = 120                        # simulated-time limit per run (optional)
wall_seconds = 60                    # wall-clock limit per run
success = "reached and collisions == 0"
keep = "failures"                    # run folders of: "nothing", "failures" or "all" runs
videos = 3                           # and a video of each of the first 3 failures
sample_seed = 0                      # the [sample]'s draws come from this seed

[grid]                               # every combination of these values
"drives.w0.error.y" = [0.0, 0.1]
"sensors.*.error" = [0.0, 0.02]      # `*`: every table at that level (here: every sensor)

[sample]                             # and, for each, `count` random draws of these
count = 20
"drives.r0.error.rotation" = {uniform = [0, 0.05]}   # or {normal = [mean, sd]}, {choice = [...]}
```

Paths are relative to the sweep file, which is also the program's working directory. The runs
are the product of the configurations, the grid's combinations, the sample's draws and the
seeds (in that order, the seed changing fastest); every grid combination gets the same draws.
A normal draw outside a key's valid range makes an ``invalid`` run: use ``uniform`` for bounds.

``keep`` (default ``"failures"``): whose run folders go in ``runs/``; a failure's has its first
and last frame too (some 35 ms of drawing per failure: ``"nothing"`` for the fastest sweep of
in-process policies). ``videos`` (default 0): how many failures, the first in the sweep's order,
are run again and filmed after the sweep (a few seconds each).
"""

from __future__ import annotations

import difflib
import hashlib
import itertools
import math
import re
import tomllib
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

import numpy as np

from simmer.errors import SweepError
from simmer.sweep.runs import ControllerKind, Keep, RunSpec
from simmer.sweep.success import DEFAULT_SUCCESS, OUTCOME_FIELDS, success_condition

__all__ = [
    "DEFAULT_SUCCESS",
    "OUTCOME_FIELDS",
    "Distribution",
    "SweepSpec",
    "load_sweep",
    "success_condition",
    "sweep_from_dict",
]

DEFAULT_WALL_SECONDS = 60.0
KNOWN_KEYS = frozenset(
    {
        "config",
        "program",
        "policy",
        "seeds",
        "grid",
        "sample",
        "sample_seed",
        "seconds",
        "wall_seconds",
        "success",
        "keep",
        "videos",
        "answer",
    }
)
KEEPS: tuple[Keep, ...] = get_args(Keep)
DistributionKind = Literal["uniform", "normal", "choice"]
DISTRIBUTIONS: dict[str, str] = {
    "uniform": "{uniform = [low, high]}",
    "normal": "{normal = [mean, standard deviation]}",
    "choice": "{choice = [value, value, ...]}",
}
FOLDER_NAME = 120
"""Characters a run folder's name may have before it is named by the run's key instead."""
MAX_RUNS = 100_000
"""Runs in a sweep (configurations x grid combinations x draws x seeds): at a second a run
on 2 cores, some 14 hours, and results.csv of some 30 MB; each run is described in memory
(about 1 KB) before the first starts. Counted before anything is built, so a sweep of 10**12
runs is refused at once."""
MAX_KEY_PARTS = 16
"""Names in a dotted key (``drives.w0.error.y`` has 4): tables nest no deeper in a
configuration, and deeper nesting ran out of recursion."""
MAX_SWEEP_FILE_BYTES = 1_000_000
"""Largest sweep file read (the examples have under 1 kB)."""
SETTINGS_CHECKED = 64
"""Grid combinations :meth:`SweepSpec.check_settings` builds at most beyond one per value."""
LIMITS = "SimMeR's limits are in docs/limits.md"
MAX_SAMPLE_NUMBER = 1e9
"""Largest size of a ``uniform`` bound, a ``normal`` mean or standard deviation: a command's
value has the same bound, and wider ones overflowed the draw (``uniform = [-1e308, 1e308]``
spans more than a float holds). Checked before any arithmetic, huge integers and infinities
included."""
MAX_LIMIT_SECONDS = 86_400.0
"""Largest ``seconds`` and ``wall_seconds`` of a run: a day (the configuration's ``timeout``
has the same bound), longer than any run of a sweep; beyond it the step count and the
system's timers overflow."""


@dataclass(frozen=True)
class Distribution:
    """Where a sampled key's values come from: ``uniform`` (low, high), ``normal`` (mean,
    standard deviation) or ``choice`` (the values, equally likely)."""

    kind: DistributionKind
    values: tuple[Any, ...]

    def draw(self, rng: np.random.Generator) -> Any:
        """One value (a Python float, or one of the choices as written)."""
        if self.kind == "uniform":
            return float(rng.uniform(*self.values))
        if self.kind == "normal":
            return float(rng.normal(*self.values))
        return self.values[int(rng.integers(len(self.values)))]

    def typical(self) -> Any:
        """A value it gives: the middle of ``uniform``, the mean of ``normal``, the first
        choice (what :meth:`SweepSpec.check_settings` tries the key with)."""
        if self.kind == "uniform":
            return (self.values[0] + self.values[1]) / 2
        return self.values[0]

    def __str__(self) -> str:
        return f"{self.kind}({', '.join(map(str, self.values))})"


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file; :meth:`runs` lists its runs in a fixed order."""

    folder: Path
    configs: tuple[Path, ...]
    kind: ControllerKind
    controller: str
    seeds: Sequence[int]
    grid: tuple[tuple[str, tuple[Any, ...]], ...]
    seconds: float | None = None
    wall_seconds: float = DEFAULT_WALL_SECONDS
    success: str = DEFAULT_SUCCESS
    sample: tuple[tuple[str, Distribution], ...] = ()
    sample_count: int = 0
    sample_seed: int = 0
    keep: Keep = "failures"
    videos: int = 0
    answer: str | None = None
    """What each run's program reads at its prompt; ``{target}`` is the run's target zone."""
    project: bool = False
    """The (first) configuration is the course project's (a robot with a gripper): results.csv
    has the project's columns and the summary its start-cell pictures."""

    @property
    def setting_columns(self) -> tuple[str, ...]:
        """The columns that make a setting (what the summary compares): ``config`` if there
        are several, then the grid's keys, named as in the sweep file."""
        swept = tuple(key for key, _ in self.grid)
        return ("config", *swept) if len(self.configs) > 1 else swept

    @property
    def columns(self) -> tuple[str, ...]:
        """The swept columns of results.csv: the setting's, then with a sample, ``sample``
        (the draw's number) and the sampled keys."""
        sampled = ("sample", *(key for key, _ in self.sample)) if self.sample else ()
        return (*self.setting_columns, *sampled)

    def draws(self) -> list[tuple[Any, ...]]:
        """The sample's draws: one tuple of values (in the sampled keys' order) per draw.
        Each key's values come from a stream of their own (from ``sample_seed`` and the key's
        name), so adding a key or raising ``count`` leaves the other draws as they were."""
        columns = []
        for key, distribution in self.sample:
            rng = _stream(self.sample_seed, key)
            columns.append([distribution.draw(rng) for _ in range(self.sample_count)])
        return list(zip(*columns, strict=True))

    @property
    def run_count(self) -> int:
        """How many runs :meth:`runs` gives, counted without making them."""
        return run_count(
            len(self.configs), [len(v) for _, v in self.grid], self.sample_count, len(self.seeds)
        )

    def runs(self) -> list[RunSpec]:
        """Every run, in order (:meth:`iter_runs`)."""
        return list(self.iter_runs())

    def iter_runs(self) -> Iterator[RunSpec]:
        """Every run, made as it is asked for: each configuration, each combination of the
        grid's values (the first key slowest), each draw of the sample, each seed."""
        keys = [key for key, _ in self.grid] + [key for key, _ in self.sample]
        draws: list[tuple[int | None, tuple[Any, ...]]] = (
            list(enumerate(self.draws())) if self.sample else [(None, ())]
        )
        for config in self.configs:
            for values in itertools.product(*(values for _, values in self.grid)):
                named = (config.name,) if len(self.configs) > 1 else ()
                for number, drawn in draws:
                    setting = (*named, *values, *((number, *drawn) if self.sample else ()))
                    for seed in self.seeds:
                        yield (
                            RunSpec(
                                config=str(config),
                                overrides=tuple(zip(keys, (*values, *drawn), strict=True)),
                                seed=seed,
                                kind=self.kind,
                                controller=self.controller,
                                folder=str(self.folder),
                                seconds=self.seconds,
                                wall_seconds=self.wall_seconds,
                                setting=setting,
                                sample=number,
                                success=self.success,
                                keep=self.keep,
                                answer=self.answer,
                            )
                        )

    def settings_to_check(self) -> Iterator[tuple[Any, ...]]:
        """Grid combinations that together use every value of every key: each value with the
        other keys at their first, then up to :data:`SETTINGS_CHECKED` combinations drawn at
        random (all of them, for a small grid). A 1,000^4 grid is checked in some 4,000
        configurations, not 10**12."""
        lists = [values for _, values in self.grid]
        combinations = math.prod(len(values) for values in lists)
        if combinations <= len(lists) + sum(map(len, lists)) + SETTINGS_CHECKED:
            yield from itertools.product(*lists)
            return
        first = tuple(values[0] for values in lists)
        yield first
        for i, values in enumerate(lists):
            for value in values[1:]:
                yield (*first[:i], value, *first[i + 1 :])
        rng = np.random.default_rng(0)
        for _ in range(SETTINGS_CHECKED):
            yield tuple(values[int(rng.integers(len(values)))] for values in lists)

    def check_settings(self) -> None:
        """Build each configuration with the grid's values (every value of every key at
        least once: :meth:`settings_to_check`), and each sampled key at a typical value, so a
        misspelt key or a value no run could use stops the sweep before it starts, naming the
        setting and the fix; :class:`SweepError`. A random draw outside a key's range later,
        or a combination not checked that no run can use, is a run's own ``invalid`` row."""
        from simmer.errors import ConfigError
        from simmer.sweep.runs import build_config

        typical = tuple((key, spread.typical()) for key, spread in self.sample)
        for config in self.configs:
            for values in self.settings_to_check():
                grid = tuple(zip((key for key, _ in self.grid), values, strict=True))
                try:
                    build_config(str(config), grid + typical)
                except (ConfigError, KeyError) as exc:
                    setting = ", ".join(f"{key} = {value!r}" for key, value in grid + typical)
                    reason = exc.args[0] if isinstance(exc, KeyError) else str(exc)
                    raise SweepError(
                        f"{config.name} with {setting or 'no overrides'} is not a valid "
                        f"configuration: {reason}"
                    ) from None

    def folder_names(self, runs: list[RunSpec]) -> dict[str, str]:
        """The name of each run's folder under ``runs/``, by run key: the setting and seed
        (``drives.w0.error.y=0.05_seed3``), or the run's key and seed if those are too long
        or two runs' names would be the same."""
        sampled = {key for key, _ in self.sample}
        names = {run.key(): _folder_name(self.columns, sampled, run) for run in runs}
        too_long = any(len(name) > FOLDER_NAME for name in names.values())
        if too_long or len(set(names.values())) < len(names):
            return {run.key(): f"{run.key()}_seed{run.seed}" for run in runs}
        return names


def _folder_name(columns: tuple[str, ...], sampled: set[str], run: RunSpec) -> str:
    """``key=value`` for each grid key, ``sampleN`` for a draw (its values are in the
    table), then ``seedN``; characters other than letters, digits and ``._=+-`` made ``-``."""
    parts = [
        f"sample{value}" if column == "sample" else f"{column.replace('*', 'all')}={value}"
        for column, value in zip(columns, run.setting, strict=True)
        if column not in sampled
    ]
    return re.sub(r"[^A-Za-z0-9._=+-]", "-", "_".join([*parts, f"seed{run.seed}"]))


def _stream(seed: int, key: str) -> np.random.Generator:
    """The random stream of one sampled key (as :meth:`Simulation.stream` makes one per
    source of noise)."""
    digest = hashlib.blake2b(key.encode("utf-8"), digest_size=8).digest()
    spawn = (int.from_bytes(digest, "little"),)
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=spawn))


def run_count(configs: int, grid: list[int], draws: int, seeds: int) -> int:
    """Runs of a sweep with these many configurations, values of each grid key, draws (0: no
    sample) and seeds."""
    return configs * math.prod(grid) * max(draws, 1) * seeds


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file (:class:`SweepError` saying what is wrong)."""
    path = Path(path)
    try:
        text = _read_text(path)
        data = tomllib.loads(_short_keys(text, path))
    except SweepError:
        raise
    except (OSError, UnicodeDecodeError) as exc:
        raise SweepError(f"cannot read {path}: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SweepError(f"{path} is not valid TOML: {exc}") from None
    except RecursionError:
        raise SweepError(f"{path}: tables or lists nested too deep to read") from None
    except ValueError as exc:  # an integer of more digits than Python converts (4,300)
        raise SweepError(f"{path} holds a number too long to read: {exc}") from None
    try:
        return sweep_from_dict(data, path.resolve().parent)
    except SweepError as exc:
        raise SweepError(f"{_where(path, text, str(exc))}: {exc}") from None


def _where(path: Path, text: str, message: str) -> str:
    """``path:line`` of the top-level key a message is about (``success: ...``), as a
    configuration's problems are placed, or ``path`` if it names none."""
    key = message.partition(":")[0]
    if key in KNOWN_KEYS:
        for number, line in enumerate(text.splitlines(), 1):
            if line.lstrip().startswith("["):
                break  # the tables begin: top-level keys come before them
            if re.match(rf"\s*[\"']?{key}[\"']?\s*=", line):
                return f"{path}:{number}"
    return str(path)


def _short_keys(text: str, path: Path) -> str:
    """``text``, unless a line's key has far more names than :data:`MAX_KEY_PARTS`: refused
    before it is parsed, since Python's TOML reader takes time growing with the square of a
    dotted key's length (6 s for 20,000 names). The exact count is checked on the parsed
    keys."""
    for line in text.splitlines():
        key = line.split("=", 1)[0] if "=" in line else line
        if key.count(".") > 4 * MAX_KEY_PARTS:
            names = key.strip().strip("[\"'").split(".")
            raise SweepError(f"{path}: {_long_key(names)}")
    return text


def _long_key(names: list[str]) -> str:
    """What is wrong with a key of these many names."""
    return (
        f"{'.'.join(names[:4])}...: a key of more than {MAX_KEY_PARTS} names (MAX_KEY_PARTS; "
        f"{LIMITS}); configuration keys have at most 5"
    )


def _read_text(path: Path) -> str:
    """A sweep file's text, at most :data:`MAX_SWEEP_FILE_BYTES` (SweepError otherwise)."""
    if path.exists() and not path.is_file():
        raise SweepError(f"{path} is not a regular file (a folder, a device or a pipe)")
    with path.open("rb") as file:
        data = file.read(MAX_SWEEP_FILE_BYTES + 1)
    if len(data) > MAX_SWEEP_FILE_BYTES:
        raise SweepError(
            f"{path} is larger than {MAX_SWEEP_FILE_BYTES:,} bytes, the limit of a sweep file "
            f"(MAX_SWEEP_FILE_BYTES; {LIMITS}): is it the right file?"
        )
    return data.decode("utf-8")


def sweep_from_dict(data: Mapping[str, Any], folder: Path) -> SweepSpec:
    """A sweep from the sweep file's data; relative paths are from ``folder``."""
    unknown = sorted(set(data) - KNOWN_KEYS)
    if unknown:
        hints = [_did_you_mean(key, KNOWN_KEYS) for key in unknown]
        raise SweepError(
            f"unknown key(s) {', '.join(unknown)}{''.join(hints)}; "
            f"known: {', '.join(sorted(KNOWN_KEYS))}"
        )
    configs = data.get("config")
    if isinstance(configs, str):
        configs = [configs]
    if not isinstance(configs, list) or not configs or not all(isinstance(c, str) for c in configs):
        raise SweepError("config: a configuration file (.toml or config.py), or a list of them")
    paths = tuple((folder / c).resolve() for c in configs)
    for config in paths:
        if config.exists() and not config.is_file():
            raise SweepError(
                f"config: {config} is not a regular file (a folder, a device or a pipe); "
                "name a configuration file (.toml or config.py)"
            )
        if not config.is_file():
            raise SweepError(f"config: no such file {config}")
    if len({config.name for config in paths}) < len(paths):
        raise SweepError("config: each file once, with different names (they name the column)")
    if ("program" in data) == ("policy" in data):
        raise SweepError(
            'name one controller: program = "python my_robot.py" or policy = "module:function"'
        )
    kind: ControllerKind = "program" if "program" in data else "policy"
    controller = data[kind]
    if not isinstance(controller, str) or not controller.strip():
        raise SweepError(f"{kind}: a non-empty string")
    if kind == "policy" and not _is_target(controller):
        raise SweepError(f'policy: "module:function", not {controller!r}')
    project = _is_project(paths[0])
    grid = _grid(_every_scenario(data.get("grid", {}), paths[0]))
    count, sample = _sample(data.get("sample", {}), {key for key, _ in grid})
    seeds = _seeds(data.get("seeds", 1))
    seed_count = seeds.stop if isinstance(seeds, range) else len(seeds)  # len() stops at 2**63
    runs = run_count(len(paths), [len(values) for _, values in grid], count, seed_count)
    if runs > MAX_RUNS:
        combinations = math.prod(len(values) for _, values in grid)
        raise SweepError(
            f"{runs:,} runs ({len(paths)} configuration(s) x {combinations:,} "
            f"grid combination(s) x {max(count, 1):,} draw(s) x {seed_count:,} seed(s)); at most "
            f"{MAX_RUNS:,} (MAX_RUNS: {LIMITS}): split the sweep into several files"
        )
    if "sample_seed" in data and not sample:
        raise SweepError("sample_seed: seeds the [sample] table's draws, and there is none")
    keep = data.get("keep", "failures")
    if keep not in KEEPS:
        raise SweepError(
            f"keep: one of {', '.join(map(repr, KEEPS))} (the runs whose folders are kept), "
            f"not {keep!r}{_did_you_mean(str(keep), KEEPS)}"
        )
    videos = _count(data, "videos", 0)
    if videos and keep == "nothing":
        raise SweepError(
            'videos: a video goes in its run\'s folder; keep = "failures" (or "all") with it'
        )
    return SweepSpec(
        folder=folder,
        configs=paths,
        kind=kind,
        controller=controller,
        seeds=seeds,
        grid=grid,
        seconds=_limit(data, "seconds", None),
        wall_seconds=_limit(data, "wall_seconds", DEFAULT_WALL_SECONDS) or DEFAULT_WALL_SECONDS,
        success=_checked_success(data.get("success", DEFAULT_SUCCESS)),
        sample=sample,
        sample_count=count,
        sample_seed=_count(data, "sample_seed", 0),
        keep=keep,
        videos=videos,
        answer=_answer(data.get("answer"), kind),
        project=project,
    )


def _answer(value: Any, kind: ControllerKind) -> str | None:
    if value is None:
        return None
    if kind != "program":
        raise SweepError("answer: what a program reads at its prompt; a policy has none")
    if not isinstance(value, str) or len(value) > 4096:
        raise SweepError(
            f'answer: text such as "{{target}}" (at most 4,096 characters), not {value!r}'
        )
    return value


def _is_project(config: Path) -> bool:
    """Whether a configuration is the course project's (a robot with a gripper)."""
    from simmer.config import load_config
    from simmer.config.zones import project_run
    from simmer.errors import ConfigError

    try:
        return project_run(load_config(config))
    except ConfigError:
        return False  # check_settings says what is wrong with it


EVERY = "all"
"""A grid's value for ``scenario.start`` (every start cell at each of four headings) or
``scenario.target`` (every drop-off zone)."""


def _every_scenario(grid: Any, config: Path) -> Any:
    """The grid with ``scenario.start = "all"`` and ``scenario.target = "all"`` written out
    from the (first) configuration's zones."""
    if not isinstance(grid, dict):
        return grid
    entries = dict(_dotted(grid, lambda _table: False))
    wanted = [key for key in ("scenario.start", "scenario.target") if entries.get(key) == EVERY]
    if not wanted:
        return grid
    from simmer.config import load_config
    from simmer.config.maze import Maze
    from simmer.config.project import HEADINGS
    from simmer.config.scenario import start_cells
    from simmer.config.zones import Zones
    from simmer.errors import ConfigError

    try:
        settings = load_config(config).settings
    except ConfigError as exc:
        raise SweepError(f"{wanted[0]} = {EVERY!r} needs a valid configuration: {exc}") from None
    zones = Zones.from_settings(settings)
    for key in wanted:
        if key == "scenario.target":
            entries[key] = sorted(zones.dropoff)
        else:
            cells = start_cells(settings, Maze.from_settings(settings), zones, "random")
            entries[key] = [f"{r},{c},{h:g}" for r, c in cells for h in HEADINGS]
        if not entries[key]:
            raise SweepError(f"[grid] {key} = {EVERY!r}: {config.name} has none")
    return entries


def _did_you_mean(word: str, choices: Any) -> str:
    close = difflib.get_close_matches(word, sorted(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _is_target(text: str) -> bool:
    module, colon, name = text.partition(":")
    parts = [*module.split("."), name]
    return bool(colon) and all(part.isidentifier() for part in parts)


def _is_count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _count(data: Mapping[str, Any], name: str, default: int) -> int:
    value = data.get(name, default)
    if not _is_count(value) or value < 0:
        raise SweepError(f"{name}: a whole number, 0 or more, not {value!r}")
    return int(value)


def _seeds(value: Any) -> Sequence[int]:
    if _is_count(value) and value > 0:
        return range(value)  # 10**12 seeds are counted, never listed
    if (
        isinstance(value, list)
        and value
        and all(_is_count(s) and s >= 0 for s in value)
        and len(set(value)) == len(value)
    ):
        return tuple(value)
    raise SweepError(
        f"seeds: a count (more than 0) or a list of distinct seeds (0 or more), not {value!r}"
    )


def _dotted(
    table: Mapping[str, Any], leaf: Callable[[Any], bool], way: tuple[str, ...] = ()
) -> list[tuple[str, Any]]:
    """A table's entries by dotted key, whether the file quoted the keys
    (``"drives.w0.error.y" = ...``) or not (``drives.w0.error.y = ...`` makes nested tables):
    nested tables are followed down to the first value that is a ``leaf``. A key of more than
    :data:`MAX_KEY_PARTS` names is a SweepError."""
    entries = []
    for key, value in table.items():
        names = (*way, *key.split("."))
        if len(names) > MAX_KEY_PARTS:
            raise SweepError(_long_key(list(names)))
        if isinstance(value, dict) and value and not leaf(value):
            entries += [(f"{key}.{inner}", v) for inner, v in _dotted(value, leaf, names)]
        else:
            entries.append((key, value))
    return entries


def _is_distribution(value: Any) -> bool:
    """A table that names a distribution, or tries to (no table in it)."""
    return bool(set(value) & set(DISTRIBUTIONS)) or not any(
        isinstance(v, dict) for v in value.values()
    )


def _grid(value: Any) -> tuple[tuple[str, tuple[Any, ...]], ...]:
    if not isinstance(value, dict):
        raise SweepError(
            '[grid]: a table of dotted keys and lists ("drives.w0.error.x" = [0, 0.1])'
        )
    grid = []
    for key, values in _dotted(value, lambda _table: False):
        if not isinstance(values, list) or not values:
            raise SweepError(f"[grid] {key}: a non-empty list of values, not {values!r}")
        seen: set[Any] = set()
        for item in values:
            frozen = _frozen(item)
            if frozen in seen:
                raise SweepError(f"[grid] {key}: {item!r:.80} is listed twice")
            seen.add(frozen)
        grid.append((key, tuple(values)))
    return tuple(grid)


def _frozen(value: Any) -> Any:
    """A TOML value as something hashable that is equal where the value is (lists, tables)."""
    if isinstance(value, list):
        return ("list", tuple(_frozen(v) for v in value))
    if isinstance(value, dict):
        return ("table", frozenset((k, _frozen(v)) for k, v in value.items()))
    return value


def _sample(value: Any, grid: set[str]) -> tuple[int, tuple[tuple[str, Distribution], ...]]:
    """The [sample] table: how many draws, and each key's distribution."""
    example = '[sample]: count = 20, then dotted keys with distributions ("drives.w0.error.y" = '
    if not isinstance(value, dict):
        raise SweepError(example + "{uniform = [0, 0.1]})")
    if not value:
        return 0, ()
    entries = dict(value)
    count = entries.pop("count", None)
    if not _is_count(count) or count < 1:
        raise SweepError(f"[sample] count: how many draws (1 or more), not {count!r}")
    sample = tuple(
        (key, _distribution(key, spec, grid)) for key, spec in _dotted(entries, _is_distribution)
    )
    if not sample:
        raise SweepError(example + "{uniform = [0, 0.1]}); it names none")
    return count, sample


def _distribution(key: str, spec: Any, grid: set[str]) -> Distribution:
    """One sampled key's distribution, checked."""
    forms = ", ".join(DISTRIBUTIONS.values())
    where = f"[sample] {key}"
    if key in grid:
        raise SweepError(f"{where}: also in [grid]; sweep a key in one of them")
    if not isinstance(spec, dict) or len(spec) != 1:
        raise SweepError(f"{where}: one distribution ({forms}), not {spec!r}")
    ((kind, values),) = spec.items()
    if kind not in DISTRIBUTIONS:
        raise SweepError(
            f"{where}: no distribution {kind!r}{_did_you_mean(kind, DISTRIBUTIONS)}; one of {forms}"
        )
    if kind == "choice":
        if not isinstance(values, list) or not values:
            raise SweepError(f"{where}: {DISTRIBUTIONS[kind]}, a non-empty list, not {values!r}")
        return Distribution("choice", tuple(values))
    if (
        not isinstance(values, list)
        or len(values) != 2
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
    ):
        raise SweepError(f"{where}: {DISTRIBUTIONS[kind]}, two numbers, not {_shown(values)}")
    if not all(-MAX_SAMPLE_NUMBER <= v <= MAX_SAMPLE_NUMBER for v in values):  # NaN too
        raise SweepError(
            f"{where}: {DISTRIBUTIONS[kind]}, numbers from {-MAX_SAMPLE_NUMBER:,.0f} to "
            f"{MAX_SAMPLE_NUMBER:,.0f} (MAX_SAMPLE_NUMBER; {LIMITS}), not {_shown(values)}"
        )
    first, second = (float(v) for v in values)
    if kind == "uniform" and first > second:
        raise SweepError(f"{where}: uniform = [low, high] with low <= high, not {values!r}")
    if kind == "normal" and second < 0:
        raise SweepError(f"{where}: normal's standard deviation is 0 or more, not {second!r}")
    return Distribution(kind, (first, second))


def _limit(data: Mapping[str, Any], name: str, default: float | None) -> float | None:
    value = data.get(name, default)
    if value is None:
        return None
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not 0 < value <= MAX_LIMIT_SECONDS  # compared before float(): 10**400 is an int
    ):
        raise SweepError(
            f"{name}: a number of seconds more than 0 and at most {MAX_LIMIT_SECONDS:,.0f} "
            f"(MAX_LIMIT_SECONDS; {LIMITS}), not {_shown(value)}"
        )
    return float(value)


def _shown(value: Any) -> str:
    """A value of the sweep file as an error message shows it: its first 80 characters (an
    integer of 10,000 digits is refused by ``repr`` itself)."""
    try:
        text = repr(value)
    except ValueError:
        return "a number too long to show"
    return text if len(text) <= 80 else f"{text[:77]}..."


def _checked_success(text: Any) -> str:
    if not isinstance(text, str):
        raise SweepError(f"success: an expression such as {DEFAULT_SUCCESS!r}")
    success_condition(text)
    return text
