"""Every command that reads a run folder, run as a real ``simmer`` process on hostile copies of
a real recorded run (issue 28, items 1, 2 and 7): a device class file the folder names is never
imported without ``--trust`` (it would leave a MARKER), nothing is written through a symbolic
link or into a pipe the folder holds (the victim outside keeps its bytes), text copied into
report.md stays text, and a long configuration name is drawn short. Each refusal is one plain
line."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from simmer.record.plots import MAX_SHOWN_CHARS, _title, read_run
from simmer.record.runfolder import MAX_REPORT_CHARS, MAX_SOURCE_CHARS

from helpers import run_simmer

pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]

DEVICE = """\
from pathlib import Path
Path(__file__).resolve().parent.parent.joinpath("MARKER").write_text("the device file ran")


class Evil:
    def __init__(self, info):
        self.d_type = "sensor"

    def simulate(self, value, environment):
        return 1.0
"""
HEADLESS = ("--headless", "--port-rx", "0", "--port-tx", "0", "--port", "0")
"""A run without a window, on free ports (tests run side by side)."""
VICTIM = b"the victim's own bytes\n"
COMMANDS = {
    "replay --check": ["replay", "--check"],
    "replay": ["replay"],  # the window's replay: refused before any window opens
    "render": ["render"],
    "plot": ["plot"],
}
"""Every command that reads a run folder, by its arguments before the folder."""
REFUSING = {"replay --check", "replay", "render"}
"""The commands that re-simulate the run, so must refuse a configuration naming code."""


def one_plain_line(done: subprocess.CompletedProcess[str], *words: str) -> str:
    """Exit status 1, no traceback, and one line on stderr holding ``words``."""
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert "Traceback" not in done.stdout + done.stderr
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, done.stderr
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real run: ``simmer run --headless --seconds 2 --record``, a process of its own."""
    base = tmp_path_factory.mktemp("recorded")
    done = run_simmer("run", *HEADLESS, "--seconds", "2", "--record", "run", cwd=base)
    assert (base / "run" / "report.json").is_file(), done.stderr
    return base / "run"


@pytest.fixture
def folder(recorded: Path, tmp_path: Path) -> Path:
    """A copy of the recorded run, in a place of its own with room outside it."""
    target = tmp_path / "inbox" / "run"
    shutil.copytree(recorded, target)
    return target


def edit_manifest(folder: Path, change: dict[str, object]) -> None:
    """Set ``config`` keys of the folder's manifest."""
    path = folder / "manifest.json"
    data = json.loads(path.read_text(encoding="utf-8"))
    data["config"].update(change)
    path.write_text(json.dumps(data), encoding="utf-8")


def name_a_device_file(folder: Path) -> Path:
    """Make the folder's configuration hold an original-SimMeR device whose class file (in the
    folder) leaves MARKER beside the folder when imported; return where MARKER would be."""
    (folder / "devices").mkdir()
    (folder / "devices" / "evil.py").write_text(DEVICE, encoding="utf-8")
    manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    devices = [
        *manifest["config"]["devices"],
        {
            "id": "e0",
            "group": "sensors",
            "kind": "simmer_device",
            "params": {
                "type": "simmer_device",
                "position": [0.0, 0.0],
                "module": "devices/evil.py",
                "class_name": "Evil",
            },
        },
    ]
    edit_manifest(folder, {"devices": devices, "base_dir": str(folder)})
    return folder / "MARKER"


@pytest.mark.parametrize("command", COMMANDS)
def test_a_device_file_a_folder_names_is_never_imported_without_trust(
    folder: Path, command: str
) -> None:
    marker = name_a_device_file(folder)
    done = run_simmer(*COMMANDS[command], folder, cwd=folder.parent)
    assert not marker.exists()  # the class file's code never ran
    if command in REFUSING:
        line = one_plain_line(done, "manifest.json", "names code", "evil.py", "--trust")
        assert "device e0" in line
    else:  # a plot re-simulates nothing: it draws, and imports nothing
        assert done.returncode == 0, done.stderr


def test_with_trust_the_device_file_runs(folder: Path) -> None:
    """The folder above is the real thing: trusted, its code runs (so the test above would
    see it run if it did)."""
    marker = name_a_device_file(folder)
    done = run_simmer("replay", "--check", "--trust", folder, cwd=folder.parent)
    assert marker.exists(), done.stderr
    assert "Traceback" not in done.stderr  # it differs: e0 is a column the recording lacks


@pytest.mark.parametrize("command", COMMANDS)
def test_a_kind_only_code_defines_is_code_too(folder: Path, command: str) -> None:
    manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    sensor = next(d for d in manifest["config"]["devices"] if d["group"] == "sensors")
    sensor["params"]["type"] = "from_a_package"
    edit_manifest(folder, {"devices": manifest["config"]["devices"]})
    done = run_simmer(*COMMANDS[command], folder, cwd=folder.parent)
    if command in REFUSING:
        one_plain_line(done, "names code", "from_a_package", "--trust")
    else:
        assert done.returncode == 0, done.stderr


# ----------------------------------------------------------------------------- no write outside

WRITTEN = {
    "plot": ["report.md", "path.png", "sensors.png", "localization.png"],
    "render": ["replay.mp4"],
}
"""What each command writes into a run folder."""
ESTIMATE = {"type": "estimate", "time": 0.5, "pose": [6.0, 42.0, 180.0], "truth": [6, 42, 180]}
"""An estimate event: with one, ``plot`` draws localization.png too."""


@pytest.mark.parametrize(
    ("command", "name"), [(c, n) for c, names in WRITTEN.items() for n in names]
)
def test_nothing_is_written_through_a_link_in_the_folder(
    folder: Path, command: str, name: str
) -> None:
    with (folder / "events.jsonl").open("a", encoding="utf-8") as file:
        file.write(json.dumps(ESTIMATE) + "\n")
    victim = folder.parent.parent / "victim"
    victim.write_bytes(VICTIM)
    (folder / name).unlink(missing_ok=True)
    (folder / name).symlink_to(victim)
    done = run_simmer(*COMMANDS[command], folder, cwd=folder.parent)
    assert victim.read_bytes() == VICTIM
    one_plain_line(done, name, "symbolic link", "move it away")
    assert (folder / name).is_symlink()  # left as it was
    assert not [p.name for p in folder.iterdir() if p.name.startswith(".")]  # no file half-made


@pytest.mark.parametrize("command", ["replay --check", "plot"])
def test_a_symlink_in_place_of_every_file_changes_nothing_outside(
    folder: Path, command: str
) -> None:
    victims = []
    for name in ("report.md", "path.png", "sensors.png", "localization.png", "replay.mp4"):
        victim = folder.parent.parent / f"victim-{name}"
        victim.write_bytes(VICTIM)
        (folder / name).unlink(missing_ok=True)
        (folder / name).symlink_to(victim)
        victims.append(victim)
    run_simmer(*COMMANDS[command], folder, cwd=folder.parent)
    assert [v.read_bytes() for v in victims] == [VICTIM] * len(victims)


@pytest.mark.parametrize(("command", "name"), [("plot", "report.md"), ("render", "replay.mp4")])
def test_a_hard_link_in_the_folder_is_replaced_not_written_into(
    folder: Path, command: str, name: str
) -> None:
    """A hard link is a regular file, so it is not refused; the new file takes its name and
    the victim, the same file under another name outside, keeps its bytes."""
    victim = folder.parent.parent / "victim"
    victim.write_bytes(VICTIM)
    (folder / name).unlink(missing_ok=True)
    os.link(victim, folder / name)
    done = run_simmer(*COMMANDS[command], folder, cwd=folder.parent)
    assert done.returncode == 0, done.stderr
    assert victim.read_bytes() == VICTIM
    assert (folder / name).stat().st_ino != victim.stat().st_ino


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_a_pipe_at_a_file_name_is_refused_not_opened(folder: Path) -> None:
    (folder / "path.png").unlink(missing_ok=True)
    os.mkfifo(folder / "path.png")  # opening it to write would wait for ever for a reader
    one_plain_line(run_simmer("plot", folder, cwd=folder.parent), "path.png", "a pipe")


def test_a_folder_that_is_a_link_is_not_written_into(folder: Path) -> None:
    link = folder.parent / "link"
    link.symlink_to(folder, target_is_directory=True)
    before = sorted(p.name for p in folder.iterdir())
    one_plain_line(run_simmer("plot", link, cwd=folder.parent), "is a symbolic link", "own path")
    assert sorted(p.name for p in folder.iterdir()) == before


def test_a_recording_is_not_made_through_a_link(tmp_path: Path) -> None:
    victim = tmp_path / "victim"
    victim.write_bytes(VICTIM)
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "events.jsonl").symlink_to(victim)
    done = run_simmer("run", *HEADLESS, "--seconds", "1", "--record", "run", cwd=tmp_path)
    one_plain_line(done, "events.jsonl", "symbolic link")
    assert victim.read_bytes() == VICTIM


# ----------------------------------------------------------------------------- copied text


def test_text_report_md_copies_from_the_manifest_stays_text(folder: Path) -> None:
    path = folder / "manifest.json"
    data = json.loads(path.read_text(encoding="utf-8"))
    data["program"] = "python x.py`\n# Owned\n<img src=x onerror=alert(1)>\n" + "y" * 10_000
    data["config"]["source"] = "``robot.toml\r\n[link](http://evil)\u202e"
    path.write_text(json.dumps(data), encoding="utf-8")
    done = run_simmer("plot", folder, cwd=folder.parent)
    assert done.returncode == 0, done.stderr
    report = (folder / "report.md").read_text(encoding="utf-8")
    assert not any(line.startswith(("# Owned", "<img")) for line in report.split("\n"))
    assert "\r" not in report
    assert "\u202e" not in report
    recorded_line = next(line for line in report.split("\n") if line.startswith("Recorded on"))
    assert "\\n# Owned\\n<img" in recorded_line  # in a code span, escaped: shown, not obeyed
    assert "y" * (MAX_REPORT_CHARS + 1) not in report
    assert "```" in recorded_line  # the fence outlasts the backticks inside


def test_a_long_configuration_name_is_drawn_short(folder: Path) -> None:
    edit_manifest(folder, {"source": "/labs/" + "a" * 10_000_000 + "$x$.toml"})
    run = read_run(folder)
    assert len(run.source) == MAX_SOURCE_CHARS
    assert len(_title(run)) < 200 + MAX_SHOWN_CHARS
    done = run_simmer("plot", folder, cwd=folder.parent)
    assert done.returncode == 0, done.stderr
    assert (folder / "report.md").stat().st_size < 10_000


@pytest.mark.parametrize("command", ["replay --check", "render"])
def test_a_long_configuration_name_is_said_short_when_it_no_longer_loads(
    folder: Path, command: str
) -> None:
    manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    manifest["config"]["source"] = "a\nb" * 1_000_000 + ".toml"
    manifest["config"]["settings"]["ppi"] = -1  # so the configuration's name is in the message
    (folder / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    line = one_plain_line(
        run_simmer(*COMMANDS[command], folder, cwd=folder.parent), "no longer loads", "ppi"
    )
    assert len(line) < MAX_SOURCE_CHARS * 2 + 300  # every newline written as two characters
