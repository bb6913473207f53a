"""``simmer new``: a folder of one's own for Lab 1."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out


@app.command(
    cls=Command,
    short_help="Make a folder of your own for Lab 1, the project, localization.",
    epilog=example("simmer new lab1", "cd lab1", "simmer check my_rover.toml"),
)
def new(
    folder: Annotated[
        Path, typer.Argument(help="The folder to make (new, or empty).", metavar="DIR")
    ],
    project: Annotated[
        bool,
        typer.Option(
            "--project",
            help="Add the project's files (docs/project.md): project.toml, "
            "project_delivery.py and its two sweep files.",
        ),
    ] = False,
    localization: Annotated[
        bool,
        typer.Option(
            "--localization",
            help="Add the localization page's files (docs/localization.md): the histogram "
            "filter, the particles example, its sweep file (and project.toml it sweeps on).",
        ),
    ] = False,
) -> None:
    """Make a folder of your own for Lab 1: the lab's rover (my_rover.toml), the example
    programs, two sweep files and a README pointing at the lab page, whose every command runs
    from this folder; --project and --localization add those pages' files, so that their
    commands run from it as written."""
    from simmer.errors import FolderExists
    from simmer.newfolder import lab_page, new_folder

    try:
        chosen = (("project", project), ("localization", localization))
        written = new_folder(folder, [name for name, wanted in chosen if wanted])
    except (FolderExists, OSError) as exc:
        err.print(f"cannot make the folder: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    out.print(f"made {folder}: {', '.join(path.name for path in written)}", markup=False)
    out.print(
        f"next: cd {folder}, then simmer check my_rover.toml; the lab page: {lab_page()}",
        markup=False,
    )
