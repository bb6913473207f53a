"""simmer.record.safefile, the one way a file is written into a run folder: what was at the
name stays whole if the writing fails, and nothing is left beside it."""

from __future__ import annotations

from pathlib import Path

import pytest

from simmer.errors import UnsafeOutput
from simmer.record.safefile import replacing, write_text


def write_failing(path: Path) -> None:
    """Write half a file at ``path``, then fail."""
    with replacing(path) as temp:
        temp.write_text("half a new", encoding="utf-8")
        raise RuntimeError("stopped midway")


def test_a_write_that_fails_leaves_the_old_file_whole_and_nothing_beside_it(
    tmp_path: Path,
) -> None:
    (tmp_path / "report.md").write_text("the old report\n", encoding="utf-8")
    with pytest.raises(RuntimeError):
        write_failing(tmp_path / "report.md")
    assert (tmp_path / "report.md").read_text(encoding="utf-8") == "the old report\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.md"]
    write_text(tmp_path / "report.md", "the new report\n")
    assert (tmp_path / "report.md").read_text(encoding="utf-8") == "the new report\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.md"]


def test_a_folder_at_the_name_is_refused_and_left(tmp_path: Path) -> None:
    (tmp_path / "path.png").mkdir()
    with pytest.raises(UnsafeOutput, match=r"path\.png is a folder: .* move it away"):
        write_text(tmp_path / "path.png", "x")
    assert (tmp_path / "path.png").is_dir()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["path.png"]


def test_a_users_own_folder_may_be_a_link_but_a_run_folder_may_not(tmp_path: Path) -> None:
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real", target_is_directory=True)
    with pytest.raises(UnsafeOutput, match="link is a symbolic link"):
        write_text(tmp_path / "link" / "report.md", "x")
    write_text(tmp_path / "link" / "clip.gif", "x", run_folder=False)
    assert (tmp_path / "real" / "clip.gif").read_text(encoding="utf-8") == "x"
