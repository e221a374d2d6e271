"""User pages speak to users: no dates of sittings, commit hashes or issue numbers in the README or the docs site.

The story of what was tried belongs in commit messages; a user page holds what amronet does, how to run it and
current tables with the command that reproduces them and the day each was measured (``measured YYYY-MM-DD``, the
one form a date may take).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
USER_PAGES = sorted([ROOT / "README.md", ROOT / "CHANGELOG.md", *(ROOT / "docs").rglob("*.md")])

FORBIDDEN = {
    "a date": re.compile(r"(?<!measured\s)\b20\d\d-[01]\d-[0-3]\d\b"),  # but the day a table was measured
    "an issue number": re.compile(r"(?<![\w&/\]])#\d{1,4}\b"),
    "a commit hash": re.compile(r"`(?=[0-9a-f]*\d)(?=[0-9a-f]*[a-f])[0-9a-f]{7,12}`"),
}


def offences(text: str) -> list[str]:
    """Every line of ``text`` holding a forbidden pattern, as ``line N: what``."""
    lines = text.splitlines()
    found = []
    for what, pattern in FORBIDDEN.items():
        for match in pattern.finditer(text):
            number = text.count("\n", 0, match.start()) + 1
            found.append(f"line {number}: {what} in {lines[number - 1].strip()[:80]!r}")
    return found


@pytest.mark.parametrize("page", USER_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_user_page_has_no_session_notes(page: Path) -> None:
    """No dates, issue numbers or commit hashes on a user page."""
    assert offences(page.read_text(encoding="utf-8")) == []


@pytest.mark.parametrize("line", [
    "Measured on 2026-11-25 in one sitting.",
    "the night of 2026-11-25, third session",
    "as issue #17 asked",
    "the code before (`2fae25c`)",
])
def test_the_patterns_catch_session_notes(line: str) -> None:
    """The check is not empty: each kind of session note is caught."""
    assert offences(line)


@pytest.mark.parametrize("line", [
    "see [the radio](radio.md#walls)",
    "colour `#1f77b4` and `&#8203;`",
    "a scenario hash `deadbeef` and a seed 20261125",
    "three rounds in one sitting, measured 2026-11-27:",
])
def test_ordinary_text_passes(line: str) -> None:
    """Anchors, colours, entities and plain numbers are not session notes."""
    assert offences(line) == []
