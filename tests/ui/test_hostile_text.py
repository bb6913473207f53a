"""Odd text a program sends is drawn, not fatal (issue 28, item 3): a belief label holding NUL,
a lone surrogate (sent as the JSON escape ``"\\ud800"``, since it cannot be UTF-8), a
bidirectional override, a BOM or a zero-width space made ``simmer run`` with a window exit 1,
lost its ``--video``, and made ``simmer render`` of the recording end in a traceback."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from helpers import FREE_PORTS, run_simmer

HOSTILE = ["\x00", "\ud800", "\u202e", "\ufeff", "\u200b"]

PROGRAM = """
from simmer.client import connect

labels = [(10.0 + 5 * i, 10.0, text) for i, text in enumerate({labels!r})]
with connect() as robot:
    print("cut", robot.show(pose=(12, 12, 0), labels=labels), flush=True)
    robot.sleep(0.2)
"""
"""Shows each hostile label alone and all together (the client writes a lone surrogate as
its JSON escape), then lets a few frames be drawn."""


@pytest.mark.slow
def test_hostile_labels_are_drawn_in_the_window_the_video_and_a_rendered_clip(
    tmp_path: Path,
) -> None:
    program = tmp_path / "labels.py"
    program.write_text(PROGRAM.format(labels=[*HOSTILE, "".join(HOSTILE)]), encoding="utf-8")
    video, folder = tmp_path / "run.mp4", tmp_path / "run"
    run = run_simmer(
        "run", *FREE_PORTS, "--seconds", "2", "--program", f"{sys.executable} {program}",
        "--video", str(video), "--record", str(folder),
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "cut 0" in run.stdout  # the belief was kept, labels and all
    assert "Traceback" not in run.stderr
    assert "video: " in run.stdout
    assert video.stat().st_size > 0
    assert "\\ud800" in (folder / "events.jsonl").read_text(encoding="utf-8")

    clip = tmp_path / "clip.mp4"
    render = run_simmer("render", str(folder), "-o", str(clip))
    assert render.returncode == 0, render.stderr
    assert "Traceback" not in render.stderr
    assert clip.stat().st_size > 0
