"""docs/cli.md is the commands' own --help: it must not drift from the code."""

from __future__ import annotations

from pathlib import Path

import click

from wiris_tools.cli import cli
from wiris_tools.cli.reference import render_reference

DOC = Path(__file__).resolve().parent.parent / "docs" / "cli.md"


def test_docs_cli_md_is_the_current_help():
    rendered = render_reference(cli)
    assert DOC.read_text(encoding="utf-8") == rendered, (
        "docs/cli.md is out of date: regenerate it with `python -m wiris_tools.cli.reference > docs/cli.md`")


def test_reference_has_every_command_and_option():
    rendered = render_reference(cli)

    def walk(group: click.Group, path: str):
        for name, command in group.commands.items():
            yield f"{path} {name}", command
            if isinstance(command, click.Group):
                yield from walk(command, f"{path} {name}")

    for path, command in walk(cli, "wiris"):
        assert f"## `{path}`" in rendered, path
        for param in command.params:
            for opt in getattr(param, "opts", []):
                if opt.startswith("--"):
                    assert opt in rendered, f"{path}: {opt}"


def test_reference_notices_a_changed_option():
    """The drift check can fail: a new option on a command changes the rendered text."""
    group = click.Group("wiris", commands=[click.Command("demo", params=[click.Option(["--one"])])])
    before = render_reference(group)
    group.commands["demo"].params.append(click.Option(["--two"], help="added later"))
    after = render_reference(group)
    assert before != after and "--two" in after and "--two" not in before
