"""The clock is one feature in one place (issue 29): real time and lockstep differ only in
``simmer/clock.py``; the runner and the transports hand it messages and bytes and never ask
which clock it is."""

from __future__ import annotations

import ast
from pathlib import Path

from helpers import REPO

SRC = REPO / "src" / "simmer"
CLOCK_USERS = [SRC / "runner.py", *sorted((SRC / "transport").glob("*.py"))]
"""Modules that must not branch on the kind of clock."""


def _lockstep_uses(path: Path) -> list[tuple[int, str]]:
    """Where ``path`` names ``lockstep`` (a name, an attribute, a parameter), except in
    passing it on to :func:`simmer.clock.make_clock` (the one place a runner picks its
    clock)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    allowed: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "make_clock":
            allowed.update(id(kw.value) for kw in node.keywords if kw.arg == "lockstep")
        if isinstance(node, ast.FunctionDef) and node.name == "__init__":
            allowed.update(id(arg) for arg in node.args.kwonlyargs if arg.arg == "lockstep")
    uses = []
    for node in ast.walk(tree):
        named = (
            (isinstance(node, ast.Name) and node.id == "lockstep")
            or (isinstance(node, ast.Attribute) and node.attr == "lockstep")
            or (isinstance(node, ast.arg) and node.arg == "lockstep")
        )
        if named and id(node) not in allowed:
            uses.append((node.lineno, ast.unparse(node)))
    return uses


def test_no_lockstep_branch_outside_the_clock_module() -> None:
    found = {
        str(path.relative_to(SRC)): uses for path in CLOCK_USERS if (uses := _lockstep_uses(path))
    }
    assert not found, f"branch on the clock object instead (simmer/clock.py): {found}"


def _counters(path: Path) -> list[str]:
    """Classes in ``path`` (other than ``typing.Protocol`` ones) that define ``took`` or
    ``taken``: a byte count."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ClassDef):
            continue
        if any(ast.unparse(base) in {"Protocol", "typing.Protocol"} for base in node.bases):
            continue
        defined = {
            item.name
            for item in node.body
            if isinstance(item, ast.FunctionDef) and item.name in {"took", "taken"}
        }
        if defined:
            found.append(f"{node.name}.{'/'.join(sorted(defined))}")
    return found


def test_only_the_clock_counts_the_bytes_taken() -> None:
    found = {
        str(path.relative_to(SRC)): names
        for path in sorted(SRC.rglob("*.py"))
        if path.name != "clock.py" and (names := _counters(path))
    }
    assert not found, f"the clock (simmer/clock.py) keeps the byte count, not: {found}"


KINDS = {"CommandText", "ClockText", "LocalizationText", "Refused"}
"""The kinds of a decoded message (``simmer.protocol.Decoded``)."""


def _kind_dispatch(path: Path) -> tuple[int, list[str]]:
    """How many ``match`` statements in ``path`` name a kind of message in their cases, and
    the kinds named anywhere else as a test (``isinstance``) or the flags the kinds replaced
    (``decoded.clock``, ``decoded.meta``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    matches = 0
    elsewhere = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Match):
            named = {
                sub.cls.id
                for case in node.cases
                for sub in ast.walk(case.pattern)
                if isinstance(sub, ast.MatchClass) and isinstance(sub.cls, ast.Name)
            }
            matches += bool(named & KINDS)
        elif _tests_a_kind(node):
            elsewhere.append(f"{node.lineno}: {ast.unparse(node)}")
    return matches, elsewhere


def _tests_a_kind(node: ast.AST) -> bool:
    """Whether ``node`` is an ``isinstance`` against a kind, or reads a replaced flag."""
    if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance":
        return any(isinstance(n, ast.Name) and n.id in KINDS for n in ast.walk(node))
    return (
        isinstance(node, ast.Attribute)
        and node.attr in {"clock", "meta"}
        and ast.unparse(node.value).endswith("decoded")
    )


def test_each_dispatcher_matches_the_kinds_of_message_once() -> None:
    """The runner and the TCP transport each decide what to do with a message in one
    ``match`` on its kind, not on flag fields."""
    for name in ("runner.py", "transport/tcp.py"):
        matches, elsewhere = _kind_dispatch(SRC / name)
        assert (matches, elsewhere) == (1, []), name


def _blocking(path: Path) -> list[str]:
    """Threads started, and waits for a reply with a timeout (a thread blocking on it), in
    ``path``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Attribute):
            continue
        thread = node.func.attr == "Thread" and ast.unparse(node.func.value) == "threading"
        waits = node.func.attr == "result" and any(kw.arg == "timeout" for kw in node.keywords)
        if thread or waits:
            found.append(f"{node.lineno}: {ast.unparse(node)}")
    return found


def test_no_transport_blocks_a_thread_on_a_reply() -> None:
    """Every transport is served by the loop thread (one concurrency model, issue 29): none
    starts a thread of its own or waits on a reply."""
    found = {
        path.name: uses
        for path in sorted((SRC / "transport").glob("*.py"))
        if (uses := _blocking(path))
    }
    assert not found, f"serve it from the bus's loop (watch, call_later): {found}"
