"""``simmer keys``: every configuration key and device setting."""

from __future__ import annotations

from typing import Annotated

import typer

from simmer.cli.app import Command, app, example, out


@app.command(
    cls=Command,
    short_help="List every configuration key and device setting.",
    epilog=example("simmer keys --markdown > keys.md"),
)
def keys(
    markdown: Annotated[
        bool, typer.Option("--markdown", help="Print the reference as Markdown.")
    ] = False,
) -> None:
    """List every configuration key and device setting, with defaults."""
    from simmer.config.reference import reference_markdown

    text = reference_markdown()
    if markdown:
        print(text, end="")
    else:  # the note for whoever maintains docs/configuration.md is not for a terminal
        from rich.markdown import Markdown

        lines = [line for line in text.splitlines() if "do not edit by hand" not in line]
        out.print(Markdown("\n".join(lines)))
