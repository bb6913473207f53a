"""The grading page in a real headless browser (Debian's chromium; scripts/setup.py --test
installs it as root where apt-get is): the leaderboard's rows in rank order as the browser
parsed them, each team's report link and video link, the side-by-side commands, and a
screenshot that is not blank."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from PIL import Image

from grade_support import grading_folder
from simmer.grade import load_grading
from simmer.grade.board import write_board

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        CHROMIUM is None,
        reason="no chromium: apt-get install -y chromium (Debian), or run "
        "scripts/setup.py --test as root, which installs it",
    ),
]
TEAMS = {"Alpha": "print('a')\n", "Beta": "print('b')\n"}


def _row(team: str, delivered: bool, folder: str) -> dict[str, str]:
    """A results.csv row as a grading writes it (the columns the board reads)."""
    return {
        "team": team,
        "scenario.target": "B1",
        "seed": "1",
        "success": str(delivered),
        "score": "100.0" if delivered else "30.0",
        "delivered_at": "40.5" if delivered else "",
        "entered_loading_at": "5.0",
        "picked_up_at": "12.0",
        "left_loading_at": "20.0" if delivered else "",
        "time": "41.0",
        "collisions": "0",
        "messages": "120",
        "nan_replies": "0",
        "status": "ok" if delivered else "error",
        "exit_status": "0" if delivered else "1",
        "detail": "" if delivered else "RuntimeError: half-way",
        "folder": folder,
    }


def _browser(*args: str) -> str:
    assert CHROMIUM is not None
    done = subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", *args],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    return done.stdout


def test_the_grading_page_as_chromium_shows_it(tmp_path: Path) -> None:
    spec = load_grading(grading_folder(tmp_path / "course", teams=TEAMS, targets=("B1",)))
    results = tmp_path / "results"
    for name in ("Alpha_target=B1_seed1", "Beta_target=B1_seed1"):
        (results / "runs" / name).mkdir(parents=True)
    (results / "runs" / "Alpha_target=B1_seed1" / "video.mp4").write_bytes(b"\0")
    rows = [
        _row("Alpha", False, "runs/Alpha_target=B1_seed1"),
        _row("Beta", True, "runs/Beta_target=B1_seed1"),
    ]
    write_board(results, spec, rows, "GRADING.toml", {})
    page = (results / "index.html").as_uri()

    dom = _browser("--dump-dom", page)
    assert dom.index(">Beta<") < dom.index(">Alpha<")  # Beta delivered: first
    assert 'href="teams/Alpha.md"' in dom
    assert 'href="runs/Alpha_target=B1_seed1/video.mp4"' in dom
    assert "simmer replay runs/Beta_target=B1_seed1 runs/Alpha_target=B1_seed1</code>" in dom
    assert dom.count("<tr") == 3

    shot = tmp_path / "page.png"
    _browser("--window-size=1200,600", f"--screenshot={shot}", page)
    with Image.open(shot) as image:
        assert image.size == (1200, 600)
        colours = image.convert("RGB").getcolors(maxcolors=1 << 16)
    assert colours is not None
    assert len(colours) > 20  # text and the failed row's tint, not a blank page
    assert (253, 236, 234) in {colour for _, colour in colours}  # the failed row's background
