"""MkDocs hook: the command-line reference, generated from the typer app.

A page that holds the marker ``<!-- cli-reference -->`` gets, in its place, the ``--help`` text of
``railride`` and of every command, each in a fenced code block, rendered at a fixed width of 100
columns (so the page does not depend on the terminal that builds the site). Registered in
``mkdocs.yml`` under ``hooks:``.
"""

from __future__ import annotations

MARKER = "<!-- cli-reference -->"
WIDTH = 100


def _help(command, name: str, parent=None) -> str:
    import click

    ctx = click.Context(command, info_name=name, parent=parent, terminal_width=WIDTH, max_content_width=WIDTH)
    return ctx.get_help()


def render() -> str:
    """The reference as Markdown: ``railride --help``, then one section per command, in the order
    ``railride --help`` lists them."""
    import click
    import typer.main

    import railride.cli

    group = typer.main.get_command(railride.cli.app)
    root = click.Context(group, info_name="railride", terminal_width=WIDTH, max_content_width=WIDTH)
    parts = ["## `railride`", "", "```text", _help(group, "railride"), "```", ""]
    for name, command in group.commands.items():
        if command.hidden:
            continue
        parts += [f"## `railride {name}`", "", "```text", _help(command, name, root), "```", ""]
    return "\n".join(parts)


def on_page_markdown(markdown: str, page, config, files) -> str:
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, render())
