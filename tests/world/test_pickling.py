"""Configurations and simulations cross into other processes (a process pool's workers), and
SimMeR's own modules import each other one way only."""

from __future__ import annotations

import ast
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest

from simmer import SimConfig, Simulation, load_config
from simmer.devices.plugins import module_name, plugin_path

from helpers import EXAMPLES, REPO, SIMMER_PY

SRC = REPO / "src"
WITH_DEVICE = SIMMER_PY / "with_device" / "config.py"


def in_fresh_process(code: str, data: bytes, cwd: Path) -> str:
    """Run ``code`` in a new interpreter (with another hash seed, elsewhere) with ``data`` (a
    pickle) on its standard input; return what it prints."""
    env = {**os.environ, "PYTHONHASHSEED": "12345", "SDL_VIDEODRIVER": "dummy"}
    done = subprocess.run(
        [sys.executable, "-c", "import pickle, sys\n" + code],
        input=data,
        capture_output=True,
        check=False,
        timeout=120,
        env=env,
        cwd=cwd,
    )
    assert done.returncode == 0, done.stderr.decode()
    return done.stdout.decode().strip()


# ----------------------------------------------------------------------------- plug-in kinds


@pytest.mark.slow
def test_a_plugin_module_has_the_same_name_in_every_process(tmp_path: Path) -> None:
    plugin = EXAMPLES / "devices" / "bumper.py"
    code = (
        "from pathlib import Path\nfrom simmer.devices.plugins import module_name\n"
        f"print(module_name(Path({str(plugin)!r})))"
    )
    assert in_fresh_process(code, b"", tmp_path) == module_name(plugin)
    assert module_name(plugin).startswith("simmer_plugin_bumper_")
    assert plugin_path(module_name(plugin)) == plugin.resolve()
    odd = tmp_path / "my-sensor.v2 ü.py"
    assert module_name(odd).isidentifier()
    assert plugin_path(module_name(odd)) == odd.resolve()
    assert plugin_path("simmer_plugin_") is None
    assert plugin_path("simmer.devices") is None


@pytest.mark.slow
def test_a_configuration_with_a_plugin_kind_runs_in_a_fresh_process(tmp_path: Path) -> None:
    config = load_config(EXAMPLES / "bumper_rover.toml")
    expected = Simulation(config).command("b0")
    code = (
        "config = pickle.loads(sys.stdin.buffer.read())\n"
        "from simmer import Simulation\n"
        "print(Simulation(config).command('b0'))\n"
    )
    assert in_fresh_process(code, pickle.dumps(config), tmp_path) == str(expected)
    assert expected == [0.0]


@pytest.mark.slow
def test_a_simulation_with_a_plugin_kind_continues_in_a_fresh_process(tmp_path: Path) -> None:
    sim = Simulation.from_config(EXAMPLES / "bumper_rover.toml", seed=7)
    sim.command("w0-20")
    sim.step(30)
    data = pickle.dumps(sim)
    sim.run_until_idle()
    code = (
        "sim = pickle.loads(sys.stdin.buffer.read())\n"
        "sim.run_until_idle()\n"
        "print(tuple(sim.robot.pose), sim.command('b0'))\n"
    )
    assert in_fresh_process(code, data, tmp_path) == f"{tuple(sim.robot.pose)} {sim.command('b0')}"


@pytest.mark.slow
def test_a_moved_plugin_file_is_named_when_unpickling_fails(tmp_path: Path) -> None:
    plugin = tmp_path / "devices" / "bumper.py"
    plugin.parent.mkdir()
    bumper = (EXAMPLES / "devices" / "bumper.py").read_text()
    plugin.write_text(bumper.replace('"bumper"', '"bumper_gone"'))
    toml = tmp_path / "rover.toml"
    toml.write_text(
        (EXAMPLES / "bumper_rover.toml").read_text().replace('"bumper"', '"bumper_gone"')
    )
    data = pickle.dumps(load_config(toml))
    plugin.unlink()
    code = (
        "try:\n    pickle.loads(sys.stdin.buffer.read())\n"
        "except ModuleNotFoundError as exc:\n    print(exc)"
    )
    said = in_fresh_process(code, data, tmp_path)
    assert said.endswith(f"runs the file {plugin}, which no longer exists")


# ----------------------------------------------------------------------------- SimMeR devices


@pytest.mark.slow
def test_a_configuration_with_a_simmer_style_device_runs_in_a_fresh_process(
    tmp_path: Path,
) -> None:
    config = load_config(WITH_DEVICE)
    assert config.device("b0").kind == "simmer_device"
    expected = Simulation(config).command("b0")
    code = (
        "config = pickle.loads(sys.stdin.buffer.read())\n"
        "from simmer import Simulation\n"
        "print(Simulation(config).command('b0'))\n"
    )
    assert in_fresh_process(code, pickle.dumps(config), tmp_path) == str(expected)


@pytest.mark.slow
def test_a_simulation_with_a_simmer_style_device_keeps_its_state(tmp_path: Path) -> None:
    sim = Simulation.from_config(WITH_DEVICE)
    sim.step(12)
    assert sim.command("b0-1") == pytest.approx([12 / 60])  # the user's object counts frames
    copy = pickle.loads(pickle.dumps(sim))
    copy.step(6)
    assert copy.command("b0-1") == pytest.approx([18 / 60])
    code = "sim = pickle.loads(sys.stdin.buffer.read())\nsim.step(3)\nprint(sim.command('b0-1'))"
    assert in_fresh_process(code, pickle.dumps(sim), tmp_path) == str([15 / 60])


def test_the_default_configuration_still_pickles() -> None:
    config: SimConfig = load_config(EXAMPLES / "simmer_default.toml")
    assert pickle.loads(pickle.dumps(config)) == config


# ----------------------------------------------------------------------------- import cycles


def module_graph(src: Path, package: str) -> dict[str, set[str]]:
    """Which of ``package``'s modules each of its modules imports, read from the source.

    Every import counts, also those inside functions (they run too, only later); those under
    ``if TYPE_CHECKING:`` do not (they never run). ``from a import b`` is an edge to ``a.b``
    if that is a module, else to ``a``. Importing ``a.b`` also runs ``a/__init__.py``, but a
    package importing its own submodules is how packages work, so that is not an edge.
    """
    files = {}
    for path in (src / package).rglob("*.py"):
        parts = path.relative_to(src).with_suffix("").parts
        is_package = parts[-1] == "__init__"
        files[".".join(parts[:-1] if is_package else parts)] = (path, is_package)

    def imports(name: str, path: Path, is_package: bool) -> set[str]:
        found: set[str] = set()
        here = name if is_package else name.rpartition(".")[0]
        for node in _running_nodes(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                found |= {alias.name for alias in node.names if alias.name in files}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parent = here.rsplit(".", node.level - 1)[0] if node.level > 1 else here
                    base = f"{parent}.{base}" if base else parent
                for alias in node.names:
                    full = f"{base}.{alias.name}"
                    if full in files:
                        found.add(full)
                    elif base in files:
                        found.add(base)
        return found - {name}

    return {name: imports(name, *where) for name, where in files.items()}


def _running_nodes(tree: ast.AST) -> list[ast.AST]:
    """Every node of ``tree`` except what sits under ``if TYPE_CHECKING:``."""
    found: list[ast.AST] = []
    pending = [tree]
    while pending:
        node = pending.pop()
        found.append(node)
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test):
                pending += child.orelse
            else:
                pending.append(child)
    return found


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle (``[a, b, a]``) in ``graph``, or None."""
    state: dict[str, str] = {}

    def visit(node: str, path: list[str]) -> list[str] | None:
        state[node] = "open"
        for target in sorted(graph[node]):
            if state.get(target) == "open":
                return [*path[path.index(target) :], target]
            if target not in state:
                cycle = visit(target, [*path, target])
                if cycle:
                    return cycle
        state[node] = "done"
        return None

    for start in sorted(graph):
        if start not in state:
            cycle = visit(start, [start])
            if cycle:
                return cycle
    return None


def test_the_cycle_finder_sees_a_cycle_through_a_lazy_import(tmp_path: Path) -> None:
    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "sub" / "__init__.py").write_text("from .b import thing\n")
    (package / "a.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import pkg.c\n"
        "def f():\n    from pkg.sub import b\n"
    )
    (package / "sub" / "b.py").write_text("from .. import a\nthing = 1\n")
    (package / "c.py").write_text("import pkg.a\n")
    graph = module_graph(tmp_path, "pkg")
    assert graph["pkg.a"] == {"pkg.sub.b"}
    assert graph["pkg.sub"] == {"pkg.sub.b"}
    assert find_cycle(graph) == ["pkg.a", "pkg.sub.b", "pkg.a"]
    (package / "sub" / "b.py").write_text("thing = 1\n")
    assert find_cycle(module_graph(tmp_path, "pkg")) is None


@pytest.mark.slow
def test_simmer_modules_import_each_other_one_way_only() -> None:
    graph = module_graph(SRC, "simmer")
    assert "simmer.devices" in graph["simmer.compat.template"]  # the graph sees the imports
    assert "simmer.config.simmer_py" in graph["simmer.config.loader"]
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


@pytest.mark.slow
def test_the_builtin_kinds_are_imported_on_first_use(tmp_path: Path) -> None:
    code = (
        "import simmer.devices\n"
        "before = 'simmer.compat.template' in sys.modules\n"
        "kind = simmer.devices.get_device_kind('simmer_device')\n"
        "print(before, kind.__name__, kind.kind, 'simmer.compat.template' in sys.modules)"
    )
    assert in_fresh_process(code, b"", tmp_path) == "False SimmerDevice simmer_device True"
