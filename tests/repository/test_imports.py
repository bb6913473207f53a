"""Headless work never imports pygame: a sweep that keeps failures but films none, a recorded
run (and its plots), and the packages under the window. Each check runs in a fresh
interpreter, so nothing another test imported counts."""

from __future__ import annotations

import ast
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import EXAMPLES, REPO

pytestmark = pytest.mark.timeout(300)

SRC = REPO / "src" / "simmer"
POLICIES = REPO / "tests" / "fixtures" / "sweep" / "sweep_policies.py"
REPORT = (
    "\nimport json, sys\n"
    "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] == 'pygame'"
    " or m.startswith('simmer.ui'))))\n"
)
"""Appended to each check: the pygame and window modules the check imported."""


def drawing_modules(code: str, cwd: Path) -> list[str]:
    """Run ``code`` in a fresh interpreter and return the pygame and :mod:`simmer.ui` modules
    it left imported."""
    done = subprocess.run(
        [sys.executable, "-c", code + REPORT],
        capture_output=True,
        text=True,
        check=False,
        timeout=240,
        cwd=cwd,
    )
    assert done.returncode == 0, done.stderr
    found: list[str] = json.loads(done.stdout.strip().splitlines()[-1])
    return found


@pytest.mark.slow
def test_the_headless_packages_import_no_pygame(tmp_path: Path) -> None:
    code = "import simmer.view, simmer.world, simmer.devices, simmer.sweep, simmer.record\n"
    code += "import simmer.colors, simmer.serve, simmer.cli\n"
    assert drawing_modules(code, tmp_path) == []


@pytest.mark.slow
def test_a_sweep_keeping_failures_without_videos_imports_no_pygame(tmp_path: Path) -> None:
    """Both kinds of run: a policy through :func:`run_sweep` (on threads, so its runs are in
    this interpreter) and a program run by the worker's own function."""
    shutil.copy(POLICIES, tmp_path)
    lab1 = EXAMPLES / "lab1_rover.toml"
    program = f'"{sys.executable}" -c "pass"'
    code = f"""
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from simmer.sweep.engine import run_sweep
from simmer.sweep.runs import execute
from simmer.sweep.spec import sweep_from_dict

here = Path({str(tmp_path)!r})
common = {{"config": {str(lab1)!r}, "keep": "failures", "seeds": 2, "success": "time >= 0"}}
policy = sweep_from_dict({{**common, "policy": "sweep_policies:drive_and_stop"}}, here)
done = run_sweep(policy, here / "out", engine=lambda: ThreadPoolExecutor(1), workers=1)
assert done.successes == 2, done
program = sweep_from_dict({{**common, "program": {program!r}, "seconds": 1}}, here)
results = [execute(run) for run in program.runs()]
assert [r.status for r in results] == ["ok", "ok"], results
assert all(r.success for r in results), results
"""
    assert drawing_modules(code, tmp_path) == []


@pytest.mark.slow
def test_a_headless_recorded_run_and_its_plots_import_no_pygame(tmp_path: Path) -> None:
    """A project run (its plots draw the zones in the window's colours) recorded from the
    command line, then plotted."""
    folder = tmp_path / "run"
    args = [
        "run",
        str(EXAMPLES / "project.toml"),
        "--headless",
        "--seconds",
        "1",
        "--speed",
        "max",
        "--record",
        str(folder),
        "--port-rx",
        "0",
        "--port-tx",
        "0",
        "--port",
        "0",
    ]
    code = f"""
from simmer.cli import app
for args in ({args!r}, ["plot", {str(folder)!r}]):
    try:
        app(args)
    except SystemExit as end:
        assert not end.code, (args, end.code)
"""
    assert drawing_modules(code, tmp_path) == []
    assert (folder / "trace.csv").stat().st_size > 0
    assert sorted(p.name for p in folder.glob("*.png")) == ["path.png", "sensors.png"]


def imported(path: Path) -> set[str]:
    """Every module ``path`` imports, at any depth of its code."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.add(node.module)
    return names


@pytest.mark.slow
def test_only_the_window_imports_pygame_and_the_view_never_imports_the_window() -> None:
    for path in sorted(SRC.rglob("*.py")):
        part = path.relative_to(SRC).parts[0]
        if part in ("ui", "data"):  # data: simmer new's copies of the examples
            continue
        names = imported(path)
        drawing = sorted(n for n in names if n.split(".")[0] == "pygame")
        if part == "compat":  # stand-ins for SimMeR's pygame.math, not pygame itself
            drawing = [n for n in drawing if n != "pygame.math"]
        assert drawing == [], path
        if part in ("view", "record", "world", "devices", "colors.py"):
            assert not any(n.startswith("simmer.ui") for n in names), path


def test_the_examples_import_only_the_public_api() -> None:
    """What students copy uses only what docs/api.md promises (``simmer._api.PUBLIC``), in
    examples/ and in ``simmer new``'s copies of them."""
    from simmer._api import PUBLIC

    paths = sorted(EXAMPLES.glob("*.py")) + sorted((SRC / "data").rglob("*.py"))
    assert len(paths) > 10
    for path in paths:
        internal = sorted(
            name for name in imported(path) if name.split(".")[0] == "simmer" and name not in PUBLIC
        )
        assert internal == [], f"{path.name} imports {internal}: use the public API"
