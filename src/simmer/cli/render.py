"""``simmer render``: a clip of a recorded run as a video."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.replay import (
    MaxSecondsOption,
    PluginOption,
    RunFolders,
    TrustOption,
    load_comparison,
    load_recording,
)


@app.command(
    cls=Command,
    short_help="Cut recorded runs (several: side by side) into a video.",
    epilog=example("simmer render runs/manual --from 5 --to 20 -o manual_clip.mp4")
    + "\n\n"
    + example("simmer render runs/team1 runs/team2 -o both.mp4"),
)
def render(
    folders: RunFolders,
    output: Annotated[
        Path | None,
        typer.Option(
            "-o",
            "--output",
            help="The clip: .mp4 (H.264) or .gif (default: replay.mp4 in the run folder; "
            "side by side: compare.mp4 beside the first).",
            show_default=False,
            metavar="FILE",
        ),
    ] = None,
    start: Annotated[
        float | None,
        typer.Option(
            "--from",
            help="Start, in seconds from the start of the run (default: its start).",
            show_default=False,
            metavar="SECONDS",
        ),
    ] = None,
    end: Annotated[
        float | None,
        typer.Option(
            "--to",
            help="End, in seconds from the start of the run (default: its end).",
            show_default=False,
            metavar="SECONDS",
        ),
    ] = None,
    trust: TrustOption = False,
    plugin: PluginOption = None,
    max_seconds: MaxSecondsOption = None,
) -> None:
    """Cut a clip of a recorded run into a video: what the window shows (with the path driven
    so far), at 30 frames per simulated second, drawn without a display. Several run folders
    of the same maze make one video of them side by side, as simmer replay shows them."""
    from simmer.errors import ReplayError
    from simmer.ui.clip import write_clip

    if len(folders) > 1:
        from simmer.ui.compare import write_comparison

        comparison = load_comparison(folders, trust, plugin, max_seconds)
        target = output if output is not None else folders[0].parent / "compare.mp4"
        try:
            count = write_comparison(comparison, target, start, end)
        except ReplayError as exc:
            err.print(str(exc), style="bold red", markup=False)
            raise typer.Exit(1) from None
        out.print(f"wrote {target} ({count} frames, {count / comparison.timeline.fps:.2f} s)")
        return
    folder = folders[0]
    recording = load_recording(folder, trust, plugin, max_seconds)
    path = output if output is not None else folder / "replay.mp4"
    try:
        frames = write_clip(recording, path, start, end, run_folder=output is None)
    except ReplayError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    seconds = frames / recording.timeline.fps
    out.print(f"wrote {path} ({frames} frames, {seconds:.2f} s)", markup=False)
