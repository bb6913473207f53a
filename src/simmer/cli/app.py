"""The ``simmer`` typer app, how its help pages are written, and where a command prints."""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import AbstractContextManager
from typing import Annotated, Any, Protocol

import typer
from rich.console import Console
from typer.core import TyperArgument, TyperCommand, TyperGroup, TyperOption


class HelpFormatter(Protocol):
    """What :meth:`Command.format_options` writes with: the formatter click gives a command.
    Typer ships its own copy of click (since 0.20, as the private ``typer._click``), which
    has no public name to type it by; a ``ctx`` of it is typed ``Any`` for the same reason."""

    def section(self, name: str) -> AbstractContextManager[None]:
        """An indented section under ``name``."""
        ...

    def write_dl(self, rows: Sequence[tuple[str, str]]) -> None:
        """Rows of a term and its help."""
        ...


class Command(TyperCommand):
    """A command whose help shows arguments as ``CONFIG`` / ``[CONFIG]`` with their help, as
    click does (typer writes ``{config}`` and ``<path>``)."""

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        """``[OPTIONS] CONFIG``: an optional argument in brackets, a required one bare."""
        pieces = [self.options_metavar] if self.options_metavar else []
        for param in self.get_params(ctx):
            if isinstance(param, TyperArgument):
                name = _argument_name(param)
                pieces.append(name if param.required else f"[{name}]")
        return pieces

    def format_options(self, ctx: Any, formatter: HelpFormatter) -> None:
        """The arguments by name and help, then the options as typer writes them."""
        params = self.get_params(ctx)
        rows = [(_argument_name(p), p.help or "") for p in params if isinstance(p, TyperArgument)]
        options = [
            record
            for p in params
            if not isinstance(p, TyperArgument) and (record := p.get_help_record(ctx))
        ]
        for title, entries in (("Arguments", rows), ("Options", options)):
            if entries:
                with formatter.section(title):
                    formatter.write_dl(entries)


def _argument_name(param: TyperArgument) -> str:
    return param.metavar or (param.name or "").upper()


class Group(TyperGroup):
    """The ``simmer`` group, whose ``--help`` costs nothing when a command is run."""

    def get_help_option(self, ctx: Any) -> TyperOption | None:
        """The help option, "not given" being False: typer coerces a value that is not a bool
        through pydantic, and building that for ``simmer run --help`` took 50 ms and 14 MB."""
        option = super().get_help_option(ctx)
        if option is not None:
            option.default = False
        return option


app = typer.Typer(
    name="simmer",
    cls=Group,
    help="SimMeR, the Simulator for Mechatronics Robots.",
    no_args_is_help=False,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # help as written: [u0] stays, no boxes, no <bool>
)
AS_COMMAND: list[bool] = []
"""Holds True when this process is the ``simmer`` command (:func:`simmer.cli.main`), not a
program that calls the app (a test): only then does ``run --program`` make it a subreaper."""
out = Console(markup=False, emoji=False, highlight=False, soft_wrap=True)
err = Console(stderr=True, markup=False, emoji=False, highlight=False, soft_wrap=True)
"""What the command prints is data (paths, messages, keys, a program's output): neither markup
(``[b]``) nor emoji codes (``:100:`` of ``robot.toml:100:``) are applied to it; a colour is a
``style``."""


def example(*lines: str) -> str:
    """A help page's example block, printed as written (click does not re-wrap a paragraph
    that starts with \\b)."""
    return "\b\nExample:\n" + "\n".join(f"  {line}" for line in lines)


def _print_version(wanted: bool) -> None:
    """``--version``: print the installed package's version and stop."""
    if wanted:
        from importlib.metadata import PackageNotFoundError, version

        try:
            out.print(f"simmer {version('simmer')}", markup=False)
        except PackageNotFoundError:  # run from a source tree without installing
            out.print("simmer (version unknown: not installed; pip install -e .)", markup=False)
        raise typer.Exit()


@app.callback()
def options(
    show_version: Annotated[
        bool,
        typer.Option(
            "--version",
            help="Print SimMeR's version and exit.",
            callback=_print_version,
            is_eager=True,
        ),
    ] = False,
) -> None:
    """SimMeR, the Simulator for Mechatronics Robots."""
