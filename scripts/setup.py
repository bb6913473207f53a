"""Set up SimMeR in a virtual environment, on Linux, macOS and Windows alike.

    python scripts/setup.py            # .venv with SimMeR (Windows: py scripts\\setup.py)
    python scripts/setup.py --test     # ... and the test tools (what ./scripts/test.sh needs)

The first time, and again only when pyproject.toml changes or the install is broken, it makes
``.venv`` in SimMeR's folder and installs SimMeR into it (editable: a change to the code needs
no reinstall); otherwise it only brings the source's bytecode up to date. ``./scripts/run.sh``
and ``./scripts/test.sh`` call it. After an install it says how to put ``simmer`` on the path
of a terminal (bash, zsh, PowerShell, cmd). It uses only the standard library, so any Python
3.11 or newer runs it.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
MINIMUM = (3, 11)
CHECK = "import importlib.metadata as m; m.version('simmer')"
"""What the environment's Python runs to tell whether SimMeR is installed in it."""


def scripts_dir(venv: Path, windows: bool) -> Path:
    """Where a virtual environment keeps its programs: ``Scripts`` on Windows, else ``bin``."""
    return venv / ("Scripts" if windows else "bin")


def venv_python(venv: Path, windows: bool) -> Path:
    """The environment's own Python."""
    return scripts_dir(venv, windows) / ("python.exe" if windows else "python")


def activation(venv: Path, windows: bool) -> list[str]:
    """How to put the environment's ``simmer`` on a terminal's path, one line per shell."""
    shown = os.path.relpath(venv) if venv.is_relative_to(Path.cwd()) else str(venv)
    if windows:
        return [
            f"  PowerShell:  {shown}\\Scripts\\Activate.ps1",
            f"  cmd:         {shown}\\Scripts\\activate.bat",
            f"  Git Bash:    source {Path(shown).as_posix()}/Scripts/activate",
        ]
    return [f"  bash, zsh:   source {shown}/bin/activate"]


def up_to_date(venv: Path, stamp: Path, windows: bool) -> bool:
    """Whether the last install is still good: its stamp is newer than pyproject.toml and the
    environment's Python finds SimMeR."""
    python = venv_python(venv, windows)
    if not (stamp.is_file() and python.is_file()):
        return False
    if (REPO / "pyproject.toml").stat().st_mtime > stamp.stat().st_mtime:
        return False
    done = subprocess.run([python, "-c", CHECK], capture_output=True, check=False)
    return done.returncode == 0


def install(venv: Path, test: bool, windows: bool) -> None:
    """Make the environment (if missing) and install SimMeR in it, with the test tools if
    ``test``."""
    print(f"setting up SimMeR in {venv} (a minute the first time) ...", flush=True)
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = str(venv_python(venv, windows))
    # The environment's own pip (22.3 or newer with Python 3.11) installs an editable
    # pyproject.toml project: upgrading it first would only cost time and a download.
    pip = [python, "-m", "pip", "--quiet", "--disable-pip-version-check"]
    target = f"{REPO}[test]" if test else str(REPO)
    subprocess.run([*pip, "install", "--editable", target], check=True)
    # Numba compiles each kernel on first use and caches it (about 20 s of CPU in all here):
    # now, rather than in the student's first run or first simmer.batch call.
    subprocess.run([python, "-m", "simmer.warmup"], check=True)


def compile_source(venv: Path, windows: bool) -> None:
    """Compile SimMeR's source to bytecode with the environment's Python (quick when it is up
    to date). Python does so itself on first import, except where writing bytecode is off
    (PYTHONDONTWRITEBYTECODE, a read-only folder): there every ``simmer`` would compile its
    modules again as it starts, about 0.3 s of CPU each time."""
    python = venv_python(venv, windows)
    quiet = subprocess.run([python, "-m", "compileall", "-q", str(REPO / "src")], check=False)
    if quiet.returncode != 0:
        print("(a file of SimMeR's source did not compile: the lines above say which)")


def pygame_clash(venv: Path, windows: bool) -> str | None:
    """A warning if the environment holds ``pygame`` beside SimMeR's ``pygame-ce`` (the lab
    manual says ``pip install pygame``): both install the same ``pygame`` package, so the
    one installed last wins and the other is left broken."""
    probe = "import importlib.metadata as m; m.version('pygame')"
    python = venv_python(venv, windows)
    done = subprocess.run([python, "-c", probe], capture_output=True, check=False)
    if done.returncode != 0:
        return None
    return (
        "warning: this environment has pygame as well as pygame-ce (which SimMeR uses; the lab "
        "manual's `pip install pygame` is not needed). They clash; to repair it:\n"
        f"  {python} -m pip uninstall -y pygame pygame-ce\n"
        f"  {python} -m pip install pygame-ce"
    )


def browser_for_tests() -> None:
    """The grading page's browser test needs a headless Chromium: install Debian's package
    when there is none, apt-get is here and this runs as root (CI); elsewhere the test is
    skipped with a line saying how to install it."""
    if shutil.which("chromium") or not shutil.which("apt-get"):
        return
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        return
    done = subprocess.run(["apt-get", "install", "-y", "chromium"], check=False)
    if done.returncode != 0:
        print("could not install chromium (apt-get install -y chromium); its test is skipped")


def main(argv: list[str] | None = None) -> int:
    """Set up (or check) the environment; 0 when it is ready."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--test", action="store_true", help="also install the test tools")
    parser.add_argument(
        "--venv", type=Path, default=REPO / ".venv", help="the environment (default: .venv)"
    )
    args = parser.parse_args(argv)
    if sys.version_info < MINIMUM:
        found = ".".join(map(str, sys.version_info[:3]))
        print(f"SimMeR needs Python 3.11 or newer; this is {found} ({sys.executable})")
        return 2
    windows = os.name == "nt"
    venv: Path = args.venv.resolve()
    stamp = venv / (".simmer-test-installed" if args.test else ".simmer-installed")
    if args.test:
        browser_for_tests()
    if up_to_date(venv, stamp, windows):
        compile_source(venv, windows)
        return 0
    try:
        install(venv, args.test, windows)
    except subprocess.CalledProcessError as exc:
        print(f"setting up SimMeR failed ({exc}); the lines above say why")
        return 1
    compile_source(venv, windows)
    stamp.touch()
    if args.test:  # SimMeR[test] includes what a plain set-up installs
        (venv / ".simmer-installed").touch()
    if (clash := pygame_clash(venv, windows)) is not None:
        print(clash)
    print("SimMeR is ready. To use `simmer` in a terminal, first run (once per terminal):")
    print("\n".join(activation(venv, windows)))
    print(f"or give its full path: {scripts_dir(venv, windows) / 'simmer'}")
    print("Then make a folder of your own for Lab 1: simmer new lab1 (see docs/lab1.md)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
