"""The sweep file: what to run (a configuration, a controller, seeds, a grid of overrides),
the limits, and what counts as success.

```toml
config = "config.py"                 # or a list of files: then a swept column `config`
program = "python3 -u dead_reckoning.py"   # or: policy = "module:function"
seeds = 4                            # or a list: [1, 5, 9]
seconds = 120                        # simulated-time limit per run (optional)
wall_seconds = 60                    # wall-clock limit per run
success = "reached and collisions == 0"

[grid]
"drives.w0.error.x" = [0.0, 0.1]
```

Paths are relative to the sweep file, which is also the program's working directory.
"""

from __future__ import annotations

import ast
import itertools
import math
import operator
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from simmer.sweep.runs import ControllerKind, RunSpec

DEFAULT_SUCCESS = "reached and collisions == 0"
DEFAULT_WALL_SECONDS = 60.0
OUTCOME_FIELDS = (
    "time",
    "first_motion",
    "reached",
    "reached_at",
    "task2_time",
    "collisions",
    "first_collision",
    "blocked_steps",
    "path_length",
    "messages",
    "commands",
    "nan_replies",
    "final_x",
    "final_y",
    "final_heading",
)
"""The outcome's fields as results.csv has them (the final pose in three columns); the names
a success condition may use."""
KNOWN_KEYS = frozenset(
    {"config", "program", "policy", "seeds", "grid", "seconds", "wall_seconds", "success"}
)


class SweepError(ValueError):
    """The sweep file is not a sweep SimMeR can run (the message says why)."""


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file; :meth:`runs` lists its runs in a fixed order."""

    folder: Path
    configs: tuple[Path, ...]
    kind: ControllerKind
    controller: str
    seeds: tuple[int, ...]
    grid: tuple[tuple[str, tuple[Any, ...]], ...]
    seconds: float | None = None
    wall_seconds: float = DEFAULT_WALL_SECONDS
    success: str = DEFAULT_SUCCESS

    @property
    def columns(self) -> tuple[str, ...]:
        """The swept columns of results.csv: ``config`` if there are several, then the grid's
        keys, named as in the sweep file."""
        swept = tuple(key for key, _ in self.grid)
        return ("config", *swept) if len(self.configs) > 1 else swept

    def runs(self) -> list[RunSpec]:
        """Every run: each configuration, each combination of the grid's values (the first key
        slowest), each seed."""
        keys = [key for key, _ in self.grid]
        runs = []
        for config in self.configs:
            for values in itertools.product(*(values for _, values in self.grid)):
                setting = ((config.name,) if len(self.configs) > 1 else ()) + tuple(values)
                for seed in self.seeds:
                    runs.append(
                        RunSpec(
                            config=str(config),
                            overrides=tuple(zip(keys, values, strict=True)),
                            seed=seed,
                            kind=self.kind,
                            controller=self.controller,
                            folder=str(self.folder),
                            seconds=self.seconds,
                            wall_seconds=self.wall_seconds,
                            setting=setting,
                        )
                    )
        return runs


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file (:class:`SweepError` saying what is wrong)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise SweepError(f"cannot read {path}: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SweepError(f"{path} is not valid TOML: {exc}") from None
    return sweep_from_dict(data, path.resolve().parent)


def sweep_from_dict(data: Mapping[str, Any], folder: Path) -> SweepSpec:
    """A sweep from the sweep file's data; relative paths are from ``folder``."""
    unknown = sorted(set(data) - KNOWN_KEYS)
    if unknown:
        raise SweepError(
            f"unknown key(s) {', '.join(unknown)}; known: {', '.join(sorted(KNOWN_KEYS))}"
        )
    configs = data.get("config")
    if isinstance(configs, str):
        configs = [configs]
    if not configs or not all(isinstance(c, str) for c in configs):
        raise SweepError("config: a configuration file (.toml or config.py), or a list of them")
    paths = tuple((folder / c).resolve() for c in configs)
    for config in paths:
        if not config.is_file():
            raise SweepError(f"config: no such file {config}")
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
    return SweepSpec(
        folder=folder,
        configs=paths,
        kind=kind,
        controller=controller,
        seeds=_seeds(data.get("seeds", 1)),
        grid=_grid(data.get("grid", {})),
        seconds=_limit(data, "seconds", None),
        wall_seconds=_limit(data, "wall_seconds", DEFAULT_WALL_SECONDS) or DEFAULT_WALL_SECONDS,
        success=_checked_success(data.get("success", DEFAULT_SUCCESS)),
    )


def _is_target(text: str) -> bool:
    module, colon, name = text.partition(":")
    parts = [*module.split("."), name]
    return bool(colon) and all(part.isidentifier() for part in parts)


def _seeds(value: Any) -> tuple[int, ...]:
    if isinstance(value, int) and not isinstance(value, bool) and value > 0:
        return tuple(range(value))
    if (
        isinstance(value, list)
        and value
        and all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in value)
        and len(set(value)) == len(value)
    ):
        return tuple(value)
    raise SweepError(
        f"seeds: a count (more than 0) or a list of distinct seeds (0 or more), not {value!r}"
    )


def _grid(value: Any) -> tuple[tuple[str, tuple[Any, ...]], ...]:
    if not isinstance(value, dict):
        raise SweepError(
            '[grid]: a table of dotted keys and lists ("drives.w0.error.x" = [0, 0.1])'
        )
    grid = []
    for key, values in value.items():
        if not isinstance(values, list) or not values:
            raise SweepError(f"[grid] {key}: a non-empty list of values, not {values!r}")
        grid.append((key, tuple(values)))
    return tuple(grid)


def _limit(data: Mapping[str, Any], name: str, default: float | None) -> float | None:
    value = data.get(name, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value < math.inf:
        raise SweepError(f"{name}: a number of seconds more than 0, not {value!r}")
    return float(value)


def _checked_success(text: Any) -> str:
    if not isinstance(text, str):
        raise SweepError(f"success: an expression such as {DEFAULT_SUCCESS!r}")
    success_condition(text)
    return text


# ----------------------------------------------------------------------------- success

_COMPARE: dict[type[ast.cmpop], Callable[[Any, Any], bool]] = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
}
_ARITHMETIC: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
}


def success_condition(text: str) -> Callable[[Mapping[str, Any]], bool]:
    """Compile a success condition over the outcome's fields (:data:`OUTCOME_FIELDS`):
    names, numbers, ``true``/``false``, + - * /, comparisons, ``and``, ``or``, ``not`` and
    parentheses; nothing else is allowed (it is parsed, never run by Python). A comparison
    with a field that has no value (``task2_time`` when the block was not reached) is false.
    Raises :class:`SweepError` naming what is not allowed."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        raise SweepError(f"success: cannot read {text!r}") from None
    _check(tree.body, text)
    return lambda fields: bool(_evaluate(tree.body, fields))


def _check(node: ast.expr, text: str) -> None:
    if isinstance(node, ast.Name):
        if node.id not in OUTCOME_FIELDS and node.id not in ("true", "false"):
            raise SweepError(f"success: {node.id!r} is not one of {', '.join(OUTCOME_FIELDS)}")
        return
    if isinstance(node, ast.Constant):
        if isinstance(node.value, int | float):  # bool included
            return
    elif isinstance(node, ast.BoolOp):
        for value in node.values:
            _check(value, text)
        return
    elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not | ast.USub):
        _check(node.operand, text)
        return
    elif isinstance(node, ast.Compare) and all(type(op) in _COMPARE for op in node.ops):
        for value in (node.left, *node.comparators):
            _check(value, text)
        return
    elif isinstance(node, ast.BinOp) and type(node.op) in _ARITHMETIC:
        _check(node.left, text)
        _check(node.right, text)
        return
    shown = ast.get_source_segment(text.strip(), node) or type(node).__name__
    raise SweepError(
        f"success: {shown!r} is not allowed (fields, numbers, comparisons, and/or/not)"
    )


def _evaluate(node: ast.expr, fields: Mapping[str, Any]) -> Any:
    if isinstance(node, ast.Name):
        return {"true": True, "false": False}.get(node.id, fields.get(node.id))
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.BoolOp):
        values = (_evaluate(value, fields) for value in node.values)
        return all(values) if isinstance(node.op, ast.And) else any(values)
    if isinstance(node, ast.UnaryOp):
        operand = _evaluate(node.operand, fields)
        if isinstance(node.op, ast.Not):
            return not operand
        return None if operand is None else -operand
    if isinstance(node, ast.Compare):
        left = _evaluate(node.left, fields)
        for op, right_node in zip(node.ops, node.comparators, strict=True):
            right = _evaluate(right_node, fields)
            if left is None or right is None or not _COMPARE[type(op)](left, right):
                return False
            left = right
        return True
    assert isinstance(node, ast.BinOp)
    left, right = _evaluate(node.left, fields), _evaluate(node.right, fields)
    if left is None or right is None:
        return None
    try:
        return _ARITHMETIC[type(node.op)](left, right)
    except ZeroDivisionError:
        return None
