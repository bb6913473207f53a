"""``simmer replay``: a recorded run re-simulated, in a window or ``--check``ed; the
re-simulation ``render`` shares."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import MAX_SIMULATED_SECONDS, number_check, refuse_tap_folder

if TYPE_CHECKING:
    from simmer.view.compare import Comparison
    from simmer.view.replay_model import Recording

RunFolders = Annotated[
    list[Path],
    typer.Argument(
        help="A run folder (simmer run --record DIR), or several recorded in the same maze "
        "to show side by side (one colour each).",
        metavar="DIR...",
    ),
]
TrustOption = Annotated[
    bool,
    typer.Option(
        "--trust",
        help="Import the plug-ins the run was recorded with (their code runs): only for a "
        "folder from someone you trust. Without it, a run with plug-ins is not re-simulated.",
    ),
]
PluginOption = Annotated[
    list[Path] | None,
    typer.Option(
        "--plugin",
        help="Re-simulate with this plug-in file (your own copy) instead of the ones the run "
        "names; repeat for each.",
        show_default=False,
    ),
]
MaxSecondsOption = Annotated[
    float | None,
    typer.Option(
        "--max-seconds",
        help="Re-simulate at most this many simulated seconds (default: 3600); a folder whose "
        "events go further is refused.",
        callback=number_check(
            "--max-seconds", "seconds", MAX_SIMULATED_SECONDS, "MAX_SIMULATED_SECONDS", zero=True
        ),
        show_default=False,
    ),
]


def load_recording(
    folder: Path, trust: bool, plugins: list[Path] | None, max_seconds: float | None
) -> Recording:
    """Re-simulate a run folder, saying whether it matches its recording; exit status 1 with
    one line if it cannot be replayed."""
    from simmer.errors import ReplayError
    from simmer.record.runfolder import MAX_RUN_SECONDS
    from simmer.view.replay_model import Recording

    out.print(f"re-simulating the run in {folder} ...", markup=False)
    try:
        recording = Recording.load(
            folder,
            trust=trust,
            plugins=plugins or None,
            max_seconds=MAX_RUN_SECONDS if max_seconds is None else max_seconds,
        )
    except ReplayError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    check = recording.check
    for i, line in enumerate(check.lines()):
        if check.matches and check.incomplete is None:
            out.print(line, markup=False)
        else:
            err.print(line, style="bold red" if i == 0 else "yellow", markup=False)
    return recording


def load_comparison(
    folders: list[Path], trust: bool, plugins: list[Path] | None, max_seconds: float | None
) -> Comparison:
    """Re-simulate several run folders to show side by side; exit status 1 with one line if
    they cannot be (one of them cannot be replayed, too many, another maze)."""
    from simmer.errors import ReplayError
    from simmer.view.compare import MAX_COMPARED, Comparison

    if len(folders) > MAX_COMPARED:
        err.print(
            f"{len(folders)} run folders: side by side shows 2 to {MAX_COMPARED} runs "
            "(MAX_COMPARED; one colour each)",
            style="bold red",
            markup=False,
        )
        raise typer.Exit(1)
    recordings = [load_recording(folder, trust, plugins, max_seconds) for folder in folders]
    try:
        return Comparison(recordings)
    except ReplayError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None


@app.command(
    cls=Command,
    short_help="Replay recorded runs (several: side by side) or --check them.",
    epilog=example("simmer replay runs/bias", "simmer replay --check runs/*")
    + "\n\n"
    + example("simmer replay grading-results/runs/Team-1_seed1 grading-results/runs/Team-2_seed1"),
)
def replay(
    folders: RunFolders,
    check: Annotated[
        bool,
        typer.Option(
            "--check",
            help="Only re-simulate and compare with the recording, without a window: exit "
            "status 1 if they differ.",
        ),
    ] = False,
    trust: TrustOption = False,
    plugin: PluginOption = None,
    max_seconds: MaxSecondsOption = None,
) -> None:
    """Replay a recorded run in a window: play, pause, speed, a timeline to drag, the commands
    beside the maze (H lists the keys). It is simulated again from the recorded configuration,
    seed and inputs, and says whether that matches the recording (and where it first differs
    if not). Several run folders of the same maze are shown side by side: one colour each, a
    legend, one timeline, a red cross on a robot once it has collided. With --check, every
    folder given is checked in turn (a TA's whole class at once): exit status 1 if any
    differs or cannot be replayed, and a last line counting them."""
    for folder in folders:
        refuse_tap_folder(folder, "replay")
    if check:
        raise typer.Exit(_check_all(folders, trust, plugin, max_seconds))
    if len(folders) > 1:
        _replay_several(folders, trust, plugin, max_seconds)
        return
    recording = load_recording(folders[0], trust, plugin, max_seconds)
    from simmer.errors import SimmerError
    from simmer.ui.replay import run_replay

    try:
        run_replay(recording, echo=lambda line: out.print(line, markup=False))
    except SimmerError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None


def _replay_several(
    folders: list[Path], trust: bool, plugins: list[Path] | None, max_seconds: float | None
) -> None:
    """``simmer replay RUN_A RUN_B ...``: the runs side by side."""
    comparison = load_comparison(folders, trust, plugins, max_seconds)
    from simmer.errors import SimmerError
    from simmer.ui.compare import run_compare

    try:
        run_compare(comparison)
    except SimmerError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None


def _check_all(
    folders: list[Path], trust: bool, plugins: list[Path] | None, max_seconds: float | None
) -> int:
    """``--check`` of each folder in turn, each one's lines as for one; the exit status (1 if
    any differs or cannot be replayed), with a count at the end when there are several."""
    failed: list[Path] = []
    for folder in folders:
        try:
            matches = load_recording(folder, trust, plugins, max_seconds).check.matches
        except typer.Exit:
            matches = False
        if not matches:
            failed.append(folder)
    if len(folders) > 1:
        line = f"{len(folders) - len(failed)} of {len(folders)} runs match their recordings"
        if failed:
            err.print(f"{line}; not: {', '.join(map(str, failed))}", style="bold red", markup=False)
        else:
            out.print(line, markup=False)
    return 1 if failed else 0
