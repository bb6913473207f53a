"""``simmer replay``: a recorded run re-simulated, in a window or ``--check``ed; the
re-simulation ``render`` shares."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import MAX_SIMULATED_SECONDS, RunFolder, number_check, refuse_tap_folder

if TYPE_CHECKING:
    from simmer.view.replay_model import Recording

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


@app.command(
    cls=Command,
    short_help="Replay a recorded run in a window (or --check it).",
    epilog=example("simmer replay runs/bias"),
)
def replay(
    folder: RunFolder,
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
    if not)."""
    refuse_tap_folder(folder, "replay")
    recording = load_recording(folder, trust, plugin, max_seconds)
    if check:
        raise typer.Exit(0 if recording.check.matches else 1)
    from simmer.errors import SimmerError
    from simmer.ui.replay import run_replay

    try:
        run_replay(recording, echo=lambda line: out.print(line, markup=False))
    except SimmerError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
