"""A new user's first hour, end to end: the set-up script makes a fresh environment, then the
README's activation line and the Lab 1 page's first commands (new folder, check, a program run)
run, as written, in a new empty folder. Every other command of every page is walked, from a
``simmer new`` folder with the repository's environment, by test_docs_walk.py.

The fresh environment takes about 20 s with pip's cache warm (the whole test about a minute on
2 cores); ``-m "not fresh"`` leaves it out.
"""

from __future__ import annotations

import importlib.util
import os
import shlex
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

from helpers import REPO

LAB_PAGE = (REPO / "docs" / "lab1.md").read_text(encoding="utf-8")
README = (REPO / "README.md").read_text(encoding="utf-8")
ACTIVATE = "source .venv/bin/activate"


def load_setup() -> ModuleType:
    """scripts/setup.py as a module (it is a script, not part of the package)."""
    spec = importlib.util.spec_from_file_location("simmer_setup", REPO / "scripts" / "setup.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_set_up_knows_each_platforms_layout(tmp_path: Path) -> None:
    setup = load_setup()
    venv = tmp_path / ".venv"
    assert setup.venv_python(venv, windows=True) == venv / "Scripts" / "python.exe"
    assert setup.venv_python(venv, windows=False) == venv / "bin" / "python"
    windows = "\n".join(setup.activation(venv, windows=True))
    assert "\\Scripts\\Activate.ps1" in windows
    assert "\\Scripts\\activate.bat" in windows
    assert setup.activation(venv, windows=False) == [f"  bash, zsh:   source {venv}/bin/activate"]
    for line in ("Activate.ps1", "activate.bat", ACTIVATE):  # what the README tells the student
        assert line in README


def test_the_set_up_installs_only_when_needed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    setup = load_setup()
    repo = tmp_path / "repo"
    repo.mkdir()
    pyproject = repo / "pyproject.toml"
    pyproject.write_text("[project]\nname = 'simmer'\n", encoding="utf-8")
    monkeypatch.setattr(setup, "REPO", repo)
    calls: list[list[str]] = []

    def fake_run(args: list[object], **_: object) -> subprocess.CompletedProcess[bytes]:
        """Log the command; make the environment's python when asked for a venv; say that
        pygame (not pygame-ce) is not installed."""
        words = [str(arg) for arg in args]
        calls.append(words)
        if words[1:3] == ["-m", "venv"]:
            python = setup.venv_python(Path(words[3]), os.name == "nt")
            python.parent.mkdir(parents=True, exist_ok=True)
            python.touch()
        missing = "version('pygame')" in words[-1]
        return subprocess.CompletedProcess(args, 1 if missing else 0, b"", b"")

    monkeypatch.setattr(setup.subprocess, "run", fake_run)

    def installs(*argv: str) -> list[str]:
        calls.clear()
        assert setup.main(["--venv", str(tmp_path / "venv"), *argv]) == 0
        return [call[-1] for call in calls if "install" in call]

    assert installs() == [str(repo)]  # a fresh clone: SimMeR, with the environment's own pip
    assert ["-m", "simmer.warmup"] in [call[1:] for call in calls]  # Numba's kernels compiled
    assert "source" in capsys.readouterr().out  # the activation line, once
    assert installs() == []  # nothing changed: straight to work
    assert calls[-1][1:] == ["-m", "compileall", "-q", str(repo / "src")]  # bytecode kept fresh
    assert capsys.readouterr().out == ""
    assert installs("--test") == [f"{repo}[test]"]  # the test tools are another stamp
    later = pyproject.stat().st_mtime + 10
    os.utime(pyproject, (later, later))
    assert installs() == [str(repo)]  # pyproject.toml changed


def on_the_page(command: str, page: str) -> str:
    """``command``, after checking that ``page`` has it word for word."""
    assert command in page, f"{command!r} is no longer on the page: update this test"
    return command


@pytest.mark.fresh
@pytest.mark.timeout(600)
def test_a_new_user_follows_the_readme_and_the_lab_page(tmp_path: Path) -> None:
    venv = tmp_path / "clone-venv"
    made = subprocess.run(
        [sys.executable, str(REPO / "scripts" / "setup.py"), "--venv", str(venv)],
        capture_output=True,
        text=True,
        check=False,
        timeout=540,
    )
    assert made.returncode == 0, made.stdout + made.stderr
    assert f"source {venv}/bin/activate" in made.stdout  # the line the student copies
    again = subprocess.run(
        [sys.executable, str(REPO / "scripts" / "setup.py"), "--venv", str(venv)],
        capture_output=True,
        text=True,
        check=True,
    )
    assert again.stdout == ""  # ready: nothing to do, nothing said
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH")}
    env |= {"SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}

    def shell(command: str, folder: Path) -> str:
        """Run ``command`` in a terminal that did the README's activation."""
        line = f"source {shlex.quote(str(venv))}/bin/activate && {command}"
        done = subprocess.run(
            ["bash", "-c", line],
            cwd=folder,
            env=env,
            capture_output=True,
            text=True,
            check=False,
            timeout=300,
        )
        assert done.returncode == 0, f"{command}\n{done.stdout}\n{done.stderr}"
        return done.stdout

    home = tmp_path / "my work"  # a space in the path, as on many laptops
    home.mkdir()
    shell(on_the_page("simmer new lab1", LAB_PAGE), home)
    lab = home / "lab1"
    assert "OK my_rover.toml" in shell(on_the_page("simmer check my_rover.toml", LAB_PAGE), lab)

    run = 'simmer run my_rover.toml --headless --program "python dead_reckoning.py"'
    ran = shell(on_the_page(run, LAB_PAGE), lab)
    assert "Noise: none (every error and bias is 0)" in ran
    assert "reached the block" in ran
    assert "0 busy (a drive still moving), 0 NaN replies" in ran

    assert sorted(p.name for p in home.iterdir()) == ["lab1"]  # nothing written elsewhere
