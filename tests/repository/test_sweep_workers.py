"""Sweep and grading workers hold no process-wide state of a run (issue 29, item 3): nothing
in ``simmer/sweep`` changes the worker's folder, its file descriptors 1 and 2 or
``sys.path``, sends an exception into a thread from outside, or reads a private attribute of
the standard library's executors. An AST scan, so a comment or a docstring does not count."""

from __future__ import annotations

import ast

from helpers import REPO

SWEEP = REPO / "src" / "simmer" / "sweep"
FORBIDDEN_CALLS = {"chdir", "fchdir", "dup2", "PyThreadState_SetAsyncExc"}
"""Functions a sweep worker must not call, by the name called (``os.chdir``: ``chdir``)."""
FORBIDDEN_ATTRIBUTES = {"_processes", "_threads", "_pending_work_items"}
"""Private records of ``concurrent.futures`` executors."""
PATH_CHANGES = {"insert", "append", "extend", "remove", "pop", "clear"}
"""Methods that change a list in place (on ``sys.path``)."""


def is_sys_path(node: ast.expr) -> bool:
    return (
        isinstance(node, ast.Attribute)
        and node.attr == "path"
        and isinstance(node.value, ast.Name)
        and node.value.id == "sys"
    )


def offences(source: str) -> list[str]:
    """What in ``source`` changes a worker's process-wide state, by line."""
    found = []
    for node in ast.walk(ast.parse(source)):
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Call):
            called = node.func
            name = called.attr if isinstance(called, ast.Attribute) else getattr(called, "id", "")
            if name in FORBIDDEN_CALLS:
                found.append(f"{line}: {name}()")
            is_method = isinstance(called, ast.Attribute)
            if is_method and name in PATH_CHANGES and is_sys_path(called.value):
                found.append(f"{line}: sys.path.{name}()")
        elif isinstance(node, ast.Attribute) and node.attr in FORBIDDEN_ATTRIBUTES:
            found.append(f"{line}: .{node.attr}")
        elif isinstance(node, ast.Assign | ast.AugAssign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                base = target.value if isinstance(target, ast.Subscript) else target
                if is_sys_path(base):
                    found.append(f"{line}: sys.path assigned")
    return found


def test_the_scan_finds_each_kind_of_change() -> None:
    source = (
        "import os, sys, ctypes\n"
        "os.chdir('x')\n"
        "os.dup2(3, 1)\n"
        "sys.path.insert(0, 'x')\n"
        "sys.path[:0] = ['x']\n"
        "sys.path += ['x']\n"
        "ctypes.pythonapi.PyThreadState_SetAsyncExc(1, None)\n"
        "pool._processes\n"
    )
    assert len(offences(source)) == 7
    assert offences("import sys\nprint(sys.path[0])\nmodules = sys.modules\n") == []


def test_sweep_code_changes_no_process_wide_state() -> None:
    found = {
        str(path.relative_to(REPO)): hits
        for path in sorted(SWEEP.rglob("*.py"))
        if (hits := offences(path.read_text(encoding="utf-8")))
    }
    assert found == {}, found
