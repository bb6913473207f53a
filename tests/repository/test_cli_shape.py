"""The ``simmer`` command is thin (issue 29): ``cli/`` a module per command, each letting typer
parse the flags and a typer-free function decide (``run``'s is ``RunOptions.from_flags``); no
module reaches into typer's or click's private parts."""

from __future__ import annotations

import ast
from pathlib import Path

from helpers import REPO

SRC = REPO / "src" / "simmer"
CLI = SRC / "cli"
LIBRARIES = ("typer", "click")
MAX_RUN_BODY_LINES = 36
"""``simmer run``'s command function below its signature and docstring (the signature grows a
line with each flag, which is declaring, not deciding); the whole function was 277 lines when
it decided what its flags meant itself."""


def _private(name: str) -> bool:
    """A dotted name of typer or click with a part that starts with an underscore."""
    parts = name.split(".")
    return parts[0] in LIBRARIES and any(part.startswith("_") for part in parts[1:])


def _private_uses(path: Path) -> list[str]:
    """typer's and click's private modules and names ``path`` imports or reads."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [alias.name for alias in node.names if _private(alias.name)]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names = [f"{node.module}.{alias.name}" for alias in node.names]
            found += [name for name in [node.module, *names] if _private(name)]
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            found += [name] if _private(name := f"{node.value.id}.{node.attr}") else []
    return found


def test_no_module_uses_typers_or_clicks_private_parts() -> None:
    used = {str(p.relative_to(SRC)): u for p in SRC.rglob("*.py") if (u := _private_uses(p))}
    assert used == {}


def test_the_cli_is_a_module_per_command() -> None:
    from simmer.cli import app

    modules = {}
    for info in app.registered_commands:
        name = info.name or getattr(info.callback, "__name__", "")
        modules[name] = getattr(info.callback, "__module__", "")
    assert len(modules) == 16
    assert modules == {name: f"simmer.cli.{name.replace('-', '_')}" for name in modules}


def test_the_run_command_only_parses_its_flags() -> None:
    tree = ast.parse((CLI / "run.py").read_text(encoding="utf-8"))
    run = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "run")
    assert run.end_lineno is not None
    body = run.body[1:]  # below the docstring
    assert run.end_lineno - body[0].lineno + 1 <= MAX_RUN_BODY_LINES


def test_the_options_of_a_run_know_nothing_of_typer() -> None:
    tree = ast.parse((SRC / "options.py").read_text(encoding="utf-8"))
    nodes = list(ast.walk(tree))
    imported = {alias.name for n in nodes if isinstance(n, ast.Import) for alias in n.names}
    imported |= {n.module or "" for n in nodes if isinstance(n, ast.ImportFrom)}
    assert not any(name.split(".")[0] in LIBRARIES for name in imported)
