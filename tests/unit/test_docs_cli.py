"""The site's command-line reference (docs/cli-reference.md) is generated from the typer app by
the MkDocs hook docs/hooks/cli_reference.py: it holds the help of `railride` and of every command."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import typer.main

import railride.cli

ROOT = Path(__file__).resolve().parents[2]


def _hook():
    spec = importlib.util.spec_from_file_location("cli_reference", ROOT / "docs" / "hooks" / "cli_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_reference_holds_the_help_of_every_command():
    hook = _hook()
    page = (ROOT / "docs" / "cli-reference.md").read_text(encoding="utf-8")
    assert hook.MARKER in page
    text = hook.on_page_markdown(page, None, None, None)
    assert hook.MARKER not in text
    assert "Usage: railride [OPTIONS] COMMAND [ARGS]..." in text
    commands = [n for n, c in typer.main.get_command(railride.cli.app).commands.items() if not c.hidden]
    assert len(commands) >= 11
    for name in commands:
        assert f"## `railride {name}`" in text
        assert f"Usage: railride {name} [OPTIONS]" in text
    assert text.count("```text") == len(commands) + 1
    # the width is fixed, whatever the terminal that builds the site
    longest = max(len(line) for block in text.split("```text")[1:] for line in block.split("```")[0].splitlines())
    assert longest <= hook.WIDTH


def test_a_page_without_the_marker_is_left_alone():
    assert _hook().on_page_markdown("# cli\n\nprose\n", None, None, None) == "# cli\n\nprose\n"


def test_the_api_reference_holds_every_public_name():
    import railride

    page = (Path(__file__).resolve().parents[2] / "docs" / "api.md").read_text(encoding="utf-8")
    documented = {
        line.split("::: ", 1)[1].strip().rsplit(".", 1)[-1] for line in page.splitlines() if line.startswith("::: ")
    }
    assert railride.__all__ and set(railride.__all__) <= documented, set(railride.__all__) - documented
