"""The repository speaks for itself: its code and documents point to nothing a reader of the
repository does not have (a design document kept elsewhere, a tracker's issue numbers).

History belongs in the commit log, figures in BENCHMARKS.md and attack results in
``crates/loops-io/tests/FUZZ.md``; a pointer such as "DESIGN §4" or "(issue 15)" leaves the
reader with a section they cannot open.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: What points outside: a design document's sections, and issue numbers of a tracker.
OUTSIDE = re.compile(r"\bDESIGN(?:\.md)?\b(?: §|'s\b)|\bDESIGN\.md\b|\b[Ii]ssues? #?\d+\b")

#: Text files whose words a reader sees.
SUFFIXES = {".rs", ".py", ".pyi", ".md", ".toml", ".c", ".h", ".hpp", ".cpp", ".txt", ".yml"}


def tracked_text_files() -> list[Path]:
    try:
        listed = subprocess.run(
            ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
        ).stdout.decode()
    except (OSError, subprocess.CalledProcessError) as error:
        pytest.skip(f"not a git checkout ({error}): the tracked files cannot be listed")
    paths = [ROOT / name for name in listed.split("\0") if name]
    return [p for p in paths if p.suffix in SUFFIXES or p.name == "Makefile"]


def outside_references(text: str) -> list[str]:
    return [m.group(0) for m in OUTSIDE.finditer(text)]


def test_no_pointer_to_documents_outside_the_repository() -> None:
    found = []
    for path in tracked_text_files():
        if path == Path(__file__).resolve():
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        for number, line in enumerate(text.splitlines(), 1):
            if outside_references(line):
                found.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()[:100]}")
    assert not found, "pointers outside the repository:\n" + "\n".join(found)


@pytest.mark.parametrize(
    ("line", "hits"),
    [
        ("Computes S_γ by arc-length skipping (DESIGN §4.1)", 1),
        ("## Fleets (issue 17)", 1),
        ("Issue 15, items 16 and 19 on the command line", 1),
        ("a choice that differs from DESIGN's KD-tree", 1),
        ("it issues a warning; the design of the engine", 0),
        ("tissue 3 and reissue 4 are words", 0),
    ],
)
def test_the_pattern_finds_pointers_and_only_them(line: str, hits: int) -> None:
    assert len(outside_references(line)) == hits
