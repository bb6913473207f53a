"""``simmer maze``: the course's mazes by name, a maze file's picture, the seeded generator
and conversions between TOML and text pictures (docs/mazes.md)."""

from __future__ import annotations

import signal
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.errors import ConfigError

if TYPE_CHECKING:
    from simmer.config.mazes import MazeSpec

maze_app = typer.Typer(
    name="maze",
    help="Mazes of your own: list the course's, show, generate and convert maze files.",
    short_help="List, show, generate and convert mazes.",
    epilog=example("simmer maze generate --seed 7 -o mazes/m7.toml"),
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,
)
app.add_typer(maze_app, name="maze")

Output = Annotated[
    Path | None,
    typer.Option(
        "--output", "-o", help="Maze file to write: .toml, or .txt for a picture.", metavar="FILE"
    ),
]
Png = Annotated[
    Path | None,
    typer.Option("--png", help="Also draw the maze with its ambiguity map as PNG.", metavar="FILE"),
]


def _load(name: str) -> MazeSpec:
    """A course maze by name, else a maze file; a one-line error and exit 1 if neither."""
    from simmer.config.mazes import COURSE_MAZES, course_maze, read_maze

    try:
        return course_maze(name) if name in COURSE_MAZES else read_maze(name)
    except ConfigError as exc:
        for issue in exc.issues:  # a maze file's problem is one line naming file, line, column
            err.print(issue.render(exc.source), style="bold red", markup=False)
        raise typer.Exit(1) from None


def _show(maze: MazeSpec, png: Path | None, title: str, comment: str = "") -> None:
    """Print the maze's picture and figures; draw it as PNG if asked."""
    import numpy as np

    from simmer.config.mazegen import measure
    from simmer.config.mazes import write_text

    out.print(write_text(maze, comment), end="", markup=False)
    figures = measure(np.array(maze.open), maze.cell, 1.0, loading_zone=len(maze.loading) == 4)
    out.print(f"; {figures.describe()}", markup=False)
    if png is not None:
        from simmer.config.models import Settings
        from simmer.record.mazepage import maze_png

        try:
            maze_png(Settings.model_validate(maze.settings_data()), png, figures.alike, title)
        except OSError as exc:
            err.print(f"cannot write {png}: {exc}", style="bold red", markup=False)
            raise typer.Exit(1) from None
        out.print(f"wrote {png}", markup=False)


@maze_app.command(
    "list", cls=Command, short_help="List the course's mazes by name.",
    epilog=example("simmer maze list"),
)  # fmt: skip
def list_mazes() -> None:
    """List the course's mazes, which a configuration names as maze = "NAME"."""
    from simmer.config.mazes import COURSE_MAZES

    for name, description in COURSE_MAZES.items():
        out.print(f"{name}: {description}", markup=False)


@maze_app.command(
    cls=Command, short_help="Show a maze: its picture, figures and (--png) ambiguity map.",
    epilog=example("simmer maze show mie444 --png mie444.png"),
)  # fmt: skip
def show(
    name: Annotated[
        str, typer.Argument(help="A course maze's name or a maze file.", metavar="MAZE")
    ],
    png: Png = None,
    output: Output = None,
) -> None:
    """Show a maze as a text picture with its loops, dead ends and ambiguity; --png draws it
    with each cell coloured by how many others look like it; -o converts it (TOML <-> text)."""
    maze = _load(name)
    _show(maze, png, name)
    if output is not None:
        _write(maze, output)


@maze_app.command(
    cls=Command, short_help="Make a course-like maze from a seed.",
    epilog=example("simmer maze generate --seed 7 --ambiguity 0.2,0.4 -o mazes/m7.toml"),
)  # fmt: skip
def generate(
    seed: Annotated[int, typer.Option(help="The maze's seed: the same seed, the same maze.")] = 0,
    style: Annotated[str, typer.Option(help="course, or perfect (micromouse-like).")] = "course",
    rows: Annotated[int | None, typer.Option(help="Rows of cells (course: 4).")] = None,
    cols: Annotated[int | None, typer.Option(help="Cells in a row (course: 8).")] = None,
    loops: Annotated[str | None, typer.Option(help="Share of loops LEAST,MOST.")] = None,
    dead_ends: Annotated[str | None, typer.Option(help="Share of dead ends LEAST,MOST.")] = None,
    ambiguity: Annotated[
        str | None, typer.Option(help="Share of look-alike cells LEAST,MOST.")
    ] = None,
    output: Output = None,
    png: Png = None,
) -> None:
    """Make a course-like maze from a seed (docs/mazes.md says what each knob does); print
    it, and write it with -o."""
    from pydantic import ValidationError

    from simmer.config.mazegen import generate as make
    from simmer.config.project import GenerateSettings
    from simmer.errors import GenerateError

    knobs: dict[str, object] = {"seed": seed, "style": style}
    for key, value in (("rows", rows), ("cols", cols)):
        if value is not None:
            knobs[key] = value
    for key, text in (("loops", loops), ("dead_ends", dead_ends), ("ambiguity", ambiguity)):
        if text is not None:
            knobs[key] = [part.strip() for part in text.split(",")]
    try:
        made = make(GenerateSettings.model_validate(knobs))
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(part) for part in first["loc"]) or "knobs"
        err.print(f"simmer maze generate: {where}: {first['msg']}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    except GenerateError as exc:
        err.print(f"simmer maze generate: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    _show(made.maze, png, f"seed {seed}", made.comment())
    if output is not None:
        _write(made.maze, output, made.comment())


def _write(maze: MazeSpec, output: Path, comment: str = "") -> None:
    from simmer.config.mazes import write_maze

    try:
        write_maze(maze, output, comment)
    except (OSError, ValueError) as exc:
        err.print(f"cannot write {output}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    out.print(f'wrote {output}; use it with maze = "{output}"', markup=False)


@maze_app.command(
    cls=Command, short_help="Edit a maze file in a window (click cells, drag the start).",
    epilog=example("simmer maze edit mazes/practice.txt"),
)  # fmt: skip
def edit(
    file: Annotated[
        Path, typer.Argument(help="Maze file (.toml or .txt); a new one starts as mie444.")
    ],
) -> None:
    """Open the maze editor: click a cell to cycle it (solid, open, start, loading, drop-off),
    drag the robot to move the start pose, R turns it, A shows the ambiguity map, S saves (an
    invalid maze is not saved: the window says why)."""
    from simmer.config.mazes import course_maze

    new = not file.exists()
    maze = course_maze("mie444") if new else _load(str(file))
    from simmer.ui.mazeedit import edit_maze

    # Ctrl-C in the terminal ends it as closing the window does: a handler that only notes it,
    # checked each frame. A KeyboardInterrupt could land inside pygame's C code and be
    # swallowed, leaving the editor open with no window to close (a test's Ctrl-C, once in a
    # few hundred); simmer run stops on a signal the same way (serve._stop_on_signals).
    interrupted: list[int] = []
    previous = None
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not ignored
        previous = signal.signal(signal.SIGINT, lambda number, _: interrupted.append(number))
    try:
        out.print(
            f"editing {file}{' (a new file: mie444 to start from)' if new else ''} in a window: "
            "S saves; Esc, closing the window or Ctrl-C here ends",
            markup=False,
        )
        saved = edit_maze(file, maze, lambda: bool(interrupted))
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    out.print(f"saved {file}" if saved else f"{file} not saved", markup=False)
