"""Every quadnav command line written in the README and docs/ is one the command line
accepts today: each is read by the real parser (flags, choices and numbers checked), so
a renamed flag or a value out of its range cannot stay in the documentation. Lines with
placeholders (MAP, DIR, FILE, [optional parts], A|B) are synopses and are left out."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from quadnav.cli.main import build_parser

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: A synopsis, not a command: upper-case placeholders, optional parts, alternatives.
PLACEHOLDER = re.compile(r"(?<![/\w.])[A-Z][A-Z0-9_]*\b(?![=:])|\[|\.\.\.|\|(?!\s*head)")


def _command_lines(page: Path) -> list[str]:
    """The ``quadnav ...`` lines of the page's code blocks (shell blocks, and ``$ quadnav``
    lines of output blocks), continuation lines joined, comments and chains split off."""
    found, block, pending = [], None, ""
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            block = line[3:].strip() if block is None else None
            continue
        if block is None:
            continue
        text = pending + line.strip()
        if text.endswith("\\"):
            pending = text[:-1] + " "
            continue
        pending = ""
        text = text.removeprefix("$ ")
        for part in re.split(r"\s(?:&&|;)\s", text):
            part = part.split(" #")[0].strip()
            if part.startswith("quadnav ") or part == "quadnav":
                found.append(part)
    return found


COMMANDS = sorted({(page.name, line) for page in PAGES for line in _command_lines(page)
                   if not PLACEHOLDER.search(line.removeprefix("quadnav"))})


def test_the_pages_have_commands_to_check():
    assert len(COMMANDS) > 25
    assert {page for page, _ in COMMANDS} >= {"README.md", "flying.md", "batch.md", "tello.md"}


@pytest.mark.parametrize(("page", "line"), COMMANDS)
def test_a_documented_command_line_is_accepted(page, line):
    argv = shlex.split(line.split(" | ")[0])[1:]
    try:
        build_parser().parse_args(argv)
    except SystemExit as stop:
        assert stop.code == 0, f"{page}: {line}"
