"""What counts as success, and how a run that did not succeed failed.

A success condition is a small expression over the outcome's fields
(:data:`OUTCOME_FIELDS`), parsed and evaluated here, never run by Python. A run that did not
succeed is put in one of :data:`FAILURES` by :func:`failure_kind`, for the ``failure`` column
of results.csv and the summary's gallery.
"""

from __future__ import annotations

import ast
import operator
from collections.abc import Callable, Mapping
from functools import lru_cache
from typing import Any

from simmer.ending import RunEnd
from simmer.errors import SweepError

DEFAULT_SUCCESS = "reached and collisions == 0"
LOCALIZATION_FIELDS = (
    "estimates",
    "first_within_at",
    "localized_at",
    "final_position_error",
    "final_heading_error",
)
"""How well the program's reported poses matched the truth (:mod:`simmer.world.localization`);
no value in a run whose program reported none."""
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
    "busy_replies",
    "over_limit",
    "blocked_moves",
    "final_x",
    "final_y",
    "final_heading",
    *LOCALIZATION_FIELDS,
)
"""The outcome's fields as results.csv has them (the final pose in three columns); the names
a success condition may use."""
PROJECT_FIELDS = (
    "target",
    "start_x",
    "start_y",
    "start_heading",
    "block_x",
    "block_y",
    "entered_loading",
    "entered_loading_at",
    "picked_up",
    "picked_up_at",
    "left_loading",
    "left_loading_at",
    "delivered",
    "delivered_at",
    "wrong_zone",
    "wrong_zone_at",
    "score",
)
"""A project run's fields besides (:class:`~simmer.world.outcome.ProjectReport`): columns of a
project sweep's results.csv, and names a success condition may use
(``delivered and collisions == 0``); in another run they have no value."""
TEXT_FIELDS = frozenset({"target", "wrong_zone"})
"""Fields whose value is text (a zone's name, or none): a condition may only test whether one
is set (``not wrong_zone``). Arithmetic or a comparison on one failed in every run
(``target < 5``: a TypeError) or built a string of gigabytes (``target * 1000000000``), so it
is refused before the first run; every other field is a number (true/false counting 1/0)."""
FAILURES = {
    "collision": "collided with a wall or the block",
    "timeout": "stopped by the simulated-time or the wall-clock limit",
    "stopped-short": "finished without reaching the block",
    "condition": "finished at the block, but the success condition was false",
    "crashed": "the controller failed, the worker died or the configuration was invalid",
}
"""How a run can fail (the ``failure`` column), in the order the summary shows them."""
PROJECT_FAILURES = {
    "collision": "collided with a wall or the block",
    "timeout": "stopped by the simulated-time or the wall-clock limit",
    "no-pickup": "finished without picking up the block",
    "not-delivered": "picked up the block but finished without delivering it",
    "wrong-zone": "delivered the block to another drop-off zone than its target",
    "condition": "delivered the block to its target, but the success condition was false",
    "crashed": "the controller failed, the worker died or the configuration was invalid",
}
"""How a project run can fail (a project sweep's ``failure`` column), in the summary's order:
the block's milestones, not Lab 1's "reached the block" (a run that picked the block up and
scored 30 did not "stop short")."""
CRASHED_STATUSES = frozenset({RunEnd.ERROR, RunEnd.CRASHED, RunEnd.INVALID})
MAX_EXPRESSION_CHARS = 1000
"""Characters of a success condition: the default has 27; a longer one is not a condition
anyone reads (and 200,000 ``not``s took gigabytes to parse)."""
MAX_EXPRESSION_DEPTH = 32
"""Operators nested in a success condition (``not not x`` is 2 deep): evaluation recurses."""


def flat_outcome(outcome: Mapping[str, Any] | None) -> dict[str, Any]:
    """An outcome's fields as the table has them (the final pose in three columns)."""
    if outcome is None:
        return {}
    fields = {k: v for k, v in outcome.items() if k != "final_pose"}
    fields["final_x"], fields["final_y"], fields["final_heading"] = outcome["final_pose"]
    return fields


def failures(project: bool) -> dict[str, str]:
    """The kinds of failure and their meanings: :data:`PROJECT_FAILURES` for a project sweep,
    :data:`FAILURES` otherwise."""
    return PROJECT_FAILURES if project else FAILURES


def failure_kind(
    status: str, fields: Mapping[str, Any], success: bool, project: bool = False
) -> str:
    """How a run failed (a key of :data:`FAILURES`, or with ``project`` of
    :data:`PROJECT_FAILURES`), or "" if it succeeded. The controller's own failure comes
    first, then a collision (the most telling cause, even if a limit ended the run later),
    then a limit, then how far it got: the block reached, or a project run's milestones."""
    if success:
        return ""
    if status in CRASHED_STATUSES or not fields:
        return "crashed"
    if fields.get("collisions"):
        return "collision"
    if status in (RunEnd.TIMEOUT, RunEnd.SECONDS):
        return "timeout"
    if project:
        if fields.get("delivered"):
            return "condition"
        if fields.get("wrong_zone"):
            return "wrong-zone"
        return "not-delivered" if fields.get("picked_up") else "no-pickup"
    return "condition" if fields.get("reached") else "stopped-short"


# ----------------------------------------------------------------------------- conditions

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


@lru_cache(maxsize=16)
def success_condition(text: str) -> Callable[[Mapping[str, Any]], bool]:
    """Compile a success condition over the outcome's fields (:data:`OUTCOME_FIELDS`):
    names, numbers, ``true``/``false``, + - * /, comparisons, ``and``, ``or``, ``not`` and
    parentheses; nothing else is allowed (it is parsed, never run by Python). A comparison
    with a field that has no value (``task2_time`` when the block was not reached) is false.
    Raises :class:`SweepError` naming what is not allowed; cached (a worker checks each run)."""
    if len(text) > MAX_EXPRESSION_CHARS:
        raise SweepError(
            f"success: {len(text):,} characters; at most {MAX_EXPRESSION_CHARS:,} (the limit "
            "of a success condition: SimMeR's MAX_EXPRESSION_CHARS in simmer/sweep/success.py)"
        )
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        raise SweepError(f"success: cannot read {text[:80]!r}") from None
    _check(tree.body, text, 0)
    return lambda fields: bool(_evaluate(tree.body, fields))


def _text_field(node: ast.expr) -> str | None:
    """The text field ``node``'s value may be (see :data:`TEXT_FIELDS`): the field itself,
    or one an ``and``/``or`` may give; None if it is a number."""
    if isinstance(node, ast.Name) and node.id in TEXT_FIELDS:
        return node.id
    if isinstance(node, ast.BoolOp):
        return next(filter(None, map(_text_field, node.values)), None)
    return None


def _numbers_only(operands: list[ast.expr], node: ast.expr, text: str) -> None:
    """Refuse arithmetic or a comparison of which an operand may be text."""
    for operand in operands:
        name = _text_field(operand)
        if name is not None:
            shown = ast.get_source_segment(text.strip(), node) or type(node).__name__
            raise SweepError(
                f"success: {shown!r}: {name} is a zone's name, not a number; it can only be "
                f"tested as true or false (`{name} and ...`, `not {name}`)"
            )


def succeeded(condition: str, outcome: Mapping[str, Any] | None) -> bool:
    """Whether a run with ``outcome`` (None: the run had none) meets ``condition``."""
    return outcome is not None and success_condition(condition)(flat_outcome(outcome))


def _check(node: ast.expr, text: str, depth: int) -> None:
    if depth > MAX_EXPRESSION_DEPTH:
        raise SweepError(
            f"success: operators nested more than {MAX_EXPRESSION_DEPTH} deep (the limit of a "
            "success condition: MAX_EXPRESSION_DEPTH in simmer/sweep/success.py); write it "
            "more simply"
        )
    depth += 1
    if isinstance(node, ast.Name):
        known = (*OUTCOME_FIELDS, *PROJECT_FIELDS)
        if node.id not in known and node.id not in ("true", "false"):
            raise SweepError(f"success: {node.id!r} is not one of {', '.join(known)}")
        return
    if isinstance(node, ast.Constant):
        if isinstance(node.value, int | float):  # bool included
            if _number(node.value) is None:
                raise SweepError(
                    f"success: {ast.get_source_segment(text.strip(), node)!s:.40}... is too "
                    "large a number (at most about 1e308)"
                )
            return
    elif isinstance(node, ast.BoolOp):
        for value in node.values:
            _check(value, text, depth)
        return
    elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not | ast.USub):
        _check(node.operand, text, depth)
        if isinstance(node.op, ast.USub):
            _numbers_only([node.operand], node, text)
        return
    elif isinstance(node, ast.Compare) and all(type(op) in _COMPARE for op in node.ops):
        for value in (node.left, *node.comparators):
            _check(value, text, depth)
        _numbers_only([node.left, *node.comparators], node, text)
        return
    elif isinstance(node, ast.BinOp) and type(node.op) in _ARITHMETIC:
        _check(node.left, text, depth)
        _check(node.right, text, depth)
        _numbers_only([node.left, node.right], node, text)
        return
    shown = ast.get_source_segment(text.strip(), node) or type(node).__name__
    raise SweepError(
        f"success: {shown!r} is not allowed (fields, numbers, comparisons, and/or/not)"
    )


def _number(value: Any) -> Any:
    """A field's or a constant's value as evaluation uses it: a number as a float (so
    arithmetic never builds a huge integer, and a run's field of any size cannot overflow
    it), text as it is, None for no value (or a number no float holds)."""
    if isinstance(value, int | float):
        try:
            return float(value)
        except OverflowError:
            return None
    return value


def _evaluate(node: ast.expr, fields: Mapping[str, Any]) -> Any:
    if isinstance(node, ast.Name):
        return {"true": 1.0, "false": 0.0}.get(node.id, _number(fields.get(node.id)))
    if isinstance(node, ast.Constant):
        return _number(node.value)
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
