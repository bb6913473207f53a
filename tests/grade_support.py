"""Team folders written as students write them, for the grading tests: the project's example
program (plain two-port sockets, an ``input()`` prompt for the target) and three variants."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

PYTHON = "/usr/bin/python3" if os.name == "posix" and os.getuid() == 0 else "python3"
"""As root a box runs as a user of its own, who may not read root's home (a pyenv there)."""
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
GOOD = (EXAMPLES / "project_delivery.py").read_text(encoding="utf-8")
SLOW_TRANSMIT = (
    "def transmit(data):\n    time.sleep(0.5)  # a slow team: it waits before each command\n"
)
CRASH_AFTER_PICKUP = (
    '        raise SystemExit("the gripper closed on nothing")\n'
    '    raise RuntimeError("team Crash: forgot to write the rest")\n'
)
HANG = '''"""Never reads its prompt: waits for a reply it never asked for."""
import time

while True:
    time.sleep(60)
'''


def programs() -> dict[str, str]:
    """Each team's robot.py, by team name, in the grading file's order."""
    slow = GOOD.replace("def transmit(data):\n", SLOW_TRANSMIT, 1)
    crash = GOOD.replace(
        '        raise SystemExit("the gripper closed on nothing")\n', CRASH_AFTER_PICKUP, 1
    )
    assert GOOD not in (slow, crash)
    return {"Hang": HANG, "Crash": crash, "Slow": slow, "Good": GOOD}


def grading_folder(
    root: Path,
    extra: str = "",
    teams: dict[str, str] | None = None,
    targets: tuple[str, ...] = ("B1", "B3"),
    wall: int = 60,
    seconds: int = 300,
) -> Path:
    """A grading folder: project.toml, a folder per team, GRADING.toml; the file's path."""
    root.mkdir(parents=True, exist_ok=True)
    shutil.copy(EXAMPLES / "project.toml", root / "project.toml")
    lines = [
        'config = "project.toml"',
        'answer = "{target}"',
        f"seconds = {seconds}",
        f"wall_seconds = {wall}",
        'success = "delivered and collisions == 0"',
        extra,
        "[scenarios]",
        "seeds = [1]",
        '"scenario.target" = ' + json.dumps(list(targets)),
    ]
    for name, program in (teams or programs()).items():
        folder = root / "teams" / name.lower()
        folder.mkdir(parents=True)
        (folder / "robot.py").write_text(program, encoding="utf-8")
        lines += [
            "",
            "[[team]]",
            f'name = "{name}"',
            f'folder = "teams/{name.lower()}"',
            f'program = "{PYTHON} -u robot.py"',
        ]
    path = root / "GRADING.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
