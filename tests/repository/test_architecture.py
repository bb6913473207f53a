"""The shape of the code (issue 20, docs/architecture.md): packages import only packages below
them, so there is no import circle; and nothing a headless run needs imports pygame.

Every import counts, at module level, inside a function or under ``TYPE_CHECKING``: a circle
hidden in a function is still a circle. The package ``simmer`` itself (its ``__init__``) is the
facade whose names are imported on first use; modules may read ``simmer.__version__``."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from helpers import REPO

SRC = REPO / "src" / "simmer"

LAYERS = [
    {"errors"},
    {
        "pose",
        "ports",
        "ending",
        "protocol",
        "proctree",
        "colors",
        "lazy",
        "untrusted",
        "_api",
    },
    {"geometry", "lockstep", "client"},
    {"devices", "console"},
    {"compat"},
    {"config"},
    {"options", "world", "scene"},
    {"localize", "transport", "batch"},
    {"clock"},
    {"runner", "record"},
    {"tap", "warmup"},
    {"view"},
    {"ui"},
    {"serve"},
    {"sweep", "newfolder"},
    {"gym"},
    {"grade", "calibrate"},
    {"cli"},
    {"__main__"},
]
"""From the bottom up, as docs/architecture.md draws them."""
LAYER = {unit: depth for depth, units in enumerate(LAYERS) for unit in units}
HEADLESS = {"world", "devices", "config", "sweep", "grade", "record", "view", "localize", "runner"}
"""Packages a headless run or a sweep uses: none may import pygame at module level."""


def unit(module: str) -> str:
    """The package (or top-level module) a module belongs to: ``simmer.config.maze`` ->
    ``config``; the package ``simmer`` itself -> ``""``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, *, top_level_only: bool = False) -> set[str]:
    """The modules ``path`` imports (every import, or those run when it is imported)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    nodes = tree.body if top_level_only else list(ast.walk(tree))
    found = set()
    package = module_name(path).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    for node in nodes:
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package[: len(package) - node.level + 1] + ([base] if base else []))
            found.add(base)
    return found


def sources() -> list[Path]:
    return [
        path
        for path in SRC.rglob("*.py")
        if "data" not in path.relative_to(SRC).parts and "shim" not in path.parts
    ]


@pytest.mark.slow
def test_every_package_imports_only_packages_below_it() -> None:
    upward = []
    for path in sources():
        here = unit(module_name(path))
        if not here:
            continue
        for name in imports(path):
            there = unit(name) if name.startswith("simmer.") else None
            if there and there != here and LAYER[there] >= LAYER[here]:
                upward.append(f"{module_name(path)} imports {name} ({here} -> {there})")
    assert not upward, "\n".join(sorted(upward))


def test_every_package_has_its_layer() -> None:
    units = {unit(module_name(path)) for path in sources()} - {""}
    assert units <= set(LAYER), f"add to LAYERS: {sorted(units - set(LAYER))}"


@pytest.mark.slow
@pytest.mark.parametrize("package", sorted(HEADLESS))
def test_a_headless_package_never_imports_pygame(package: str) -> None:
    """Following module-level imports from the package (what importing it runs, its parent
    packages included), pygame is never reached. (Drawing a video or a failure's frame in a
    sweep imports the window's code where it draws; tests/test_imports.py runs them.)"""
    by_name = {module_name(path): path for path in sources()}
    seen: set[str] = set()
    todo = [name for name in by_name if unit(name) == package]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        for imported in imports(by_name[name], top_level_only=True):
            assert imported.split(".")[0] != "pygame", f"{name} imports {imported}"
            module = imported
            while module and module not in by_name:  # `from simmer.x import y` of a name
                module = module.rpartition(".")[0]
            while module:  # importing a module imports its packages' __init__ too
                todo.append(module)
                module = module.rpartition(".")[0]


WHOLE = {"repository", "fixtures"}
"""Test folders about the whole: the repository (layers, imports, scripts, docs, examples, a
fresh clone) and the files the tests read."""


def test_the_tests_mirror_the_source() -> None:
    """Each test folder is a package or a module of ``src/simmer`` (a large module, ``cli``,
    has a folder of files, one per command), so a module's tests are found by its name."""
    tests = REPO / "tests"
    units = {path.stem for path in SRC.iterdir() if not path.name.startswith(("_", "."))}
    folders = {path.name for path in tests.iterdir() if path.is_dir()} - {"__pycache__"}
    assert folders - WHOLE <= units, sorted(folders - WHOLE - units)
    loose = [path.stem.removeprefix("test_") for path in tests.glob("test_*.py")]
    assert all(name.split("_")[0] in units for name in loose), loose
