"""``simmer new``: a student's lab folder whose files are the examples, made without touching a
folder that has files."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.config import load_config
from simmer.newfolder import PARTS, new_folder

from helpers import EXAMPLES, REPO

TEMPLATE = REPO / "src/simmer/data/new"
LAB1_FILES = (
    "README.md",
    "dead_reckoning.py",
    "my_rover.toml",
    "obstacle_avoidance.py",
    "sweep_dead_reckoning.toml",
    "sweep_obstacle_avoidance.toml",
)


def test_simmer_new_makes_a_lab_folder_whose_files_are_the_examples(tmp_path: Path) -> None:
    folder = tmp_path / "lab1"
    result = CliRunner().invoke(app, ["new", str(folder)])
    assert result.exit_code == 0, result.output
    names = sorted(path.name for path in folder.iterdir())
    assert names == list(LAB1_FILES)
    for copy, original in (
        ("my_rover.toml", "lab1_rover.toml"),
        ("dead_reckoning.py", "dead_reckoning.py"),
        ("obstacle_avoidance.py", "obstacle_avoidance.py"),
    ):  # one program and one rover, whichever folder a student starts from
        assert (folder / copy).read_bytes() == (EXAMPLES / original).read_bytes(), copy
    readme = (folder / "README.md").read_text(encoding="utf-8")
    assert str(REPO / "docs" / "lab1.md") in readme
    assert "{lab_page}" not in readme
    assert "simmer check my_rover.toml" in result.output
    assert (
        load_config(folder / "my_rover.toml").settings
        == load_config(EXAMPLES / "lab1_rover.toml").settings
    )


def test_the_new_folders_sweep_files_name_its_own_rover_and_programs() -> None:
    for name in ("sweep_dead_reckoning.toml", "sweep_obstacle_avoidance.toml"):
        text = (TEMPLATE / name).read_text(encoding="utf-8")
        assert 'config = "my_rover.toml"' in text
        program = re.search(r'^program = "python -u (\w+\.py)"', text, re.M)
        assert program is not None
        assert (TEMPLATE / program.group(1)).is_file()


def test_simmer_new_changes_nothing_in_a_folder_with_files(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("mine", encoding="utf-8")
    result = CliRunner().invoke(app, ["new", str(tmp_path)])
    assert result.exit_code == 1
    assert "a folder with files in it already" in result.output
    assert [path.name for path in tmp_path.iterdir()] == ["notes.txt"]
    (tmp_path / "empty").mkdir()
    assert len(new_folder(tmp_path / "empty")) == 6  # an empty folder is fine


def test_simmer_new_copies_only_the_templates_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An installed package has a __pycache__ beside the example programs: not copied."""
    package = tmp_path / "package"
    template = package / "data" / "new"
    (template / "__pycache__").mkdir(parents=True)
    (template / "README.md").write_text("see {lab_page}", encoding="utf-8")
    monkeypatch.setattr("simmer.newfolder.files", lambda _: package)
    written = new_folder(tmp_path / "lab1")
    assert [path.name for path in written] == ["README.md"]
    assert "{lab_page}" not in written[0].read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("flags", "added"),
    [
        (["--project"], PARTS["project"]),
        (["--localization"], PARTS["localization"]),
        (["--project", "--localization"], (*PARTS["project"], *PARTS["localization"])),
    ],
)
def test_simmer_new_adds_the_project_and_localization_pages_files(
    tmp_path: Path, flags: list[str], added: tuple[str, ...]
) -> None:
    folder = tmp_path / "mine"
    result = CliRunner().invoke(app, ["new", str(folder), *flags])
    assert result.exit_code == 0, result.output
    names = {path.name for path in folder.iterdir()}
    assert names == {*LAB1_FILES, *added}
    for name in added:  # the examples themselves; a sweep runs the folder's python
        copy = (folder / name).read_text(encoding="utf-8")
        original = (EXAMPLES / name).read_text(encoding="utf-8")
        if name.startswith("sweep_"):
            assert re.search(r'^program = "python -u ', copy, re.M), name
            assert (
                copy.splitlines()[5:]
                == original.replace("python3 -u", "python -u").splitlines()[5:]
            )
        else:
            assert copy == original, name


def test_a_plain_simmer_new_is_lab_1_alone(tmp_path: Path) -> None:
    written = new_folder(tmp_path / "lab1")
    assert {path.name for path in written} == set(LAB1_FILES)
    with pytest.raises(ValueError, match="no part 'gym'"):
        new_folder(tmp_path / "other", ["gym"])
