"""The bus is two parts with one job each (issue 29): ``transport/loop.py`` waits (sockets,
timers, wake-ups) and knows nothing of requests; ``transport/request_queue.py`` queues requests
and knows nothing of sockets or timers; ``CommandBus`` only puts them together."""

from __future__ import annotations

import ast
from pathlib import Path

from helpers import REPO

TRANSPORT = REPO / "src" / "simmer" / "transport"
QUEUE_WORDS = ("request", "queue", "answer", "client", "reply")
LOOP_MODULES = {"selectors", "heapq", "os", "time", "weakref"}


def _class(path: Path, name: str) -> ast.ClassDef:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == name)


def _names(cls: ast.ClassDef) -> set[str]:
    """The methods and ``self.`` attributes a class defines."""
    names = {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}
    for node in ast.walk(cls):
        stored = isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store)
        if stored and isinstance(node.value, ast.Name) and node.value.id == "self":
            names.add(node.attr)
    return names


def _runtime_imports(path: Path) -> set[str]:
    """Top-level modules ``path`` imports outside ``if TYPE_CHECKING:``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
    return found


def test_the_loop_holds_no_requests() -> None:
    names = _names(_class(TRANSPORT / "loop.py", "SelectorLoop"))
    found = sorted(n for n in names if any(word in n.lower() for word in QUEUE_WORDS))
    assert not found, f"requests belong in request_queue.py, not the loop: {found}"
    assert not {m for m in _runtime_imports(TRANSPORT / "loop.py") if "request" in m}


def test_the_queue_neither_selects_nor_keeps_timers() -> None:
    imports = _runtime_imports(TRANSPORT / "request_queue.py")
    assert not imports & LOOP_MODULES, f"the queue imports {sorted(imports & LOOP_MODULES)}"
    assert "simmer.transport.loop" not in imports, "the queue gets its loop; it does not make one"
    names = _names(_class(TRANSPORT / "request_queue.py", "RequestQueue"))
    found = sorted(n for n in names if any(w in n for w in ("select", "timer", "watch", "wake")))
    assert not found, f"sockets and timers belong in loop.py, not the queue: {found}"


def test_the_bus_only_puts_the_two_together() -> None:
    """Every method of ``CommandBus`` is a line or two handing over to one of its parts."""
    bus = _class(TRANSPORT / "bus.py", "CommandBus")
    state = _names(bus) - {n.name for n in bus.body if isinstance(n, ast.FunctionDef)}
    assert state == {"loop", "requests"}
    long = [
        n.name
        for n in bus.body
        if isinstance(n, ast.FunctionDef) and len(n.body) - isinstance(n.body[0], ast.Expr) > 2
    ]
    assert not long, f"CommandBus should delegate, not decide: {long}"
    assert not _runtime_imports(TRANSPORT / "bus.py") & LOOP_MODULES
