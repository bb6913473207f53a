"""A sweep's output folder resumed (``simmer sweep --resume``) may come from someone else: a
symbolic link where the sweep writes results.csv, summary.md, a picture or a kept run's folder
is refused in one line, and the file it points at keeps its bytes (issue 28, item 2)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import EXAMPLES, REPO

pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]

SIMMER = Path(sys.executable).with_name("simmer")
POLICIES = REPO / "tests" / "fixtures" / "sweep" / "sweep_policies.py"
VICTIM = b"the victim's own bytes\n"


def sweep(folder: Path, *more: str) -> subprocess.CompletedProcess[str]:
    """``simmer sweep sweep.toml -o out --workers 1 MORE`` as a new process in ``folder``."""
    return subprocess.run(
        [SIMMER, "sweep", "sweep.toml", "-o", "out", "--workers", "1", *more],
        cwd=folder,
        env={**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"},
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
    )


@pytest.fixture(scope="module")
def swept(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished sweep of one run, kept (keep = "all"), by a real ``simmer sweep``."""
    folder = tmp_path_factory.mktemp("swept")
    shutil.copy(POLICIES, folder)
    (folder / "sweep.toml").write_text(
        f"config = '{EXAMPLES / 'lab1_rover.toml'}'\n"
        "policy = 'sweep_policies:drive_and_stop'\n"
        "seeds = 1\n"
        "keep = 'all'\n",
        encoding="utf-8",
    )
    done = sweep(folder)
    assert done.returncode == 0, done.stderr
    return folder


@pytest.fixture
def copy(swept: Path, tmp_path: Path) -> Path:
    target = tmp_path / "sweep"
    shutil.copytree(swept, target, symlinks=True)
    return target


@pytest.mark.parametrize("name", ["results.csv", "summary.md", "runs"])
def test_a_link_in_a_resumed_sweep_folder_is_not_written_through(copy: Path, name: str) -> None:
    out = copy / "out"
    victim = copy.parent / "victim"
    if name == "runs":  # a kept run's folder is replaced: not under a link
        victim.mkdir()
        (victim / "precious").write_bytes(VICTIM)
        shutil.rmtree(out / "runs")
        (out / "runs").symlink_to(victim, target_is_directory=True)
        rows = (out / "results.csv").read_text(encoding="utf-8").splitlines()
        (out / "results.csv").write_text(rows[0] + "\n", encoding="utf-8")  # run it again
    else:
        victim.write_bytes(VICTIM)
        if name == "results.csv":  # a copy of the results, so that resuming runs nothing
            victim.write_bytes((out / name).read_bytes() + VICTIM)
        (out / name).unlink()
        (out / name).symlink_to(victim)
    before = victim.read_bytes() if victim.is_file() else None
    done = sweep(copy, "--resume")
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert "Traceback" not in done.stdout + done.stderr
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert "symbolic link" in lines[-1], done.stderr
    if name == "runs":
        assert sorted(p.name for p in victim.iterdir()) == ["precious"]
        assert (victim / "precious").read_bytes() == VICTIM
    else:
        assert victim.read_bytes() == before
