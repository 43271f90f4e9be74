"""The CLI reference (`docs/cli.md`), rendered from the commands' own `--help`.

The reference is generated so that it cannot drift from the code: `tests/test_cli_reference.py` renders it
again and fails when `docs/cli.md` differs. Regenerate with

    python -m wiris_tools.cli.reference > docs/cli.md
"""

from __future__ import annotations

import sys
from collections.abc import Iterator

import click

# The width the help text is wrapped at, fixed so the file does not depend on the terminal it was made in.
HELP_WIDTH = 100

HEADER = """\
# `wiris` command reference

Generated from the commands' `--help` by `python -m wiris_tools.cli.reference > docs/cli.md`;
`tests/test_cli_reference.py` fails when this file and the code disagree. Exit codes everywhere: 0 success,
1 invalid input or failed operation, 2 usage error.
"""


def _commands(group: click.Group, ctx: click.Context) -> Iterator[tuple[click.Command, click.Context]]:
    """Every command under `group`, depth first in name order, each with its own context."""
    for name in sorted(group.list_commands(ctx)):
        command = group.get_command(ctx, name)
        if command is None or command.hidden:
            continue
        sub = _context(command, name, ctx)
        yield command, sub
        if isinstance(command, click.Group):
            yield from _commands(command, sub)


def _context(command: click.Command, name: str, parent: click.Context | None) -> click.Context:
    """The context click would make for `command` (its context_settings, e.g. `-h` as a help option, which
    children inherit), at the fixed width."""
    settings = {**command.context_settings, "terminal_width": HELP_WIDTH, "max_content_width": HELP_WIDTH}
    return click.Context(command, info_name=name, parent=parent, **settings)


def render_reference(root: click.Group) -> str:
    """Markdown with one section per command: its path as heading and its `--help` as a code block."""
    top = _context(root, "wiris", None)
    sections = [HEADER]
    for command, ctx in [(root, top), *_commands(root, top)]:
        sections.append(f"## `{ctx.command_path}`\n\n```text\n{command.get_help(ctx).rstrip()}\n```\n")
    return "\n".join(sections)


def main() -> None:
    from wiris_tools.cli import cli

    sys.stdout.write(render_reference(cli))


if __name__ == "__main__":
    main()
