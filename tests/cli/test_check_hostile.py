"""``simmer check`` on the unlucky and the hostile (issue 18, item 9): a configuration that is
not a regular file says so, unread; a plug-in calling ``os._exit`` is reported, not obeyed."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.timeout(120)

SIMMER = Path(sys.executable).with_name("simmer")


def check(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [SIMMER, "check", *args], check=False, capture_output=True, text=True, timeout=60
    )


@pytest.mark.slow
@pytest.mark.parametrize("path", ["/dev/zero", "."])
def test_a_configuration_that_is_not_a_regular_file_says_so(path: str) -> None:
    done = check(path)
    assert done.returncode == 1
    assert f"{path}: is not a regular file (a folder, a device or a pipe)" in done.stderr


@pytest.mark.slow
def test_a_plugin_calling_os_exit_is_reported_not_obeyed(tmp_path: Path) -> None:
    (tmp_path / "quits.py").write_text("import os\nos._exit(9)\n")
    (tmp_path / "robot.toml").write_text('plugins = ["quits.py"]\n')
    done = check(tmp_path / "robot.toml")
    assert done.returncode == 1, done.stderr  # check's own status, not the plug-in's 9
    assert "plugins[0]: importing quits.py failed at line 2" in done.stderr
    assert "os._exit(9) was called" in done.stderr
    assert "Traceback" not in done.stderr
