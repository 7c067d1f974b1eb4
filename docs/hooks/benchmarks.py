"""MkDocs hook: the Benchmarks page, made at build time from the repository's BENCHMARKS.md
(which the benchmark scripts rewrite section by section), with an index of which script or
command writes each section. Links that point into the repository rather than the site become
code spans; the figures under ``docs/`` are the site's own files."""

from __future__ import annotations

import re
from pathlib import Path

from markdown.extensions.toc import slugify
from mkdocs.structure.files import File

PAGE = "benchmarks.md"
COMMAND = re.compile(r"`([^`]*(?:benches/|cargo (?:run|bench)|bash )[^`]*)`")
HEADING = re.compile(r"^(##+) (.+)$", re.M)


def slug(title: str, seen: dict[str, int]) -> str:
    """The anchor MkDocs' toc extension gives a heading (``_1``, ``_2`` for repeated titles)."""
    anchor = slugify(re.sub(r"[`*]", "", title), "-")
    count = seen.get(anchor, 0)
    seen[anchor] = count + 1
    return f"{anchor}_{count}" if count else anchor


def sections(text: str) -> list[tuple[int, str, str]]:
    """Each heading (level, title) with the command that writes its section: the first one its
    text names; else its parent section's; else, before the first section a script owns
    (``<!-- name -->``), the one the page's preamble names; else ''."""
    found: list[tuple[int, str, str]] = []
    heads = list(HEADING.finditer(text))
    first = heads[0].start() if heads else len(text)
    preamble = COMMAND.search(text, 0, first)
    owned_from = text.find("<!--")
    parent = ""
    for index, head in enumerate(heads):
        end = heads[index + 1].start() if index + 1 < len(heads) else len(text)
        level = len(head.group(1))
        command = COMMAND.search(text, head.end(), end)
        if command:
            name = command.group(1)
        elif level > 2:
            name = parent
        elif preamble and (owned_from < 0 or head.start() < owned_from):
            name = preamble.group(1)
        else:
            name = ""
        if level == 2:
            parent = name
        found.append((level, head.group(2), name))
    return found


def rewrite(text: str) -> str:
    """BENCHMARKS.md's links as the site needs them."""
    text = text.replace("](docs/", "](")
    text = text.replace("](README.md)", "](index.md)")
    text = re.sub(r"\[([^\]]+)\]\(((?:benches|crates)/[^)]+)\)", r"`\2`", text)
    return text


def page(root: Path) -> str:
    text = (root / "BENCHMARKS.md").read_text()
    body = rewrite(text.split("\n", 1)[1])  # without its title
    seen: dict[str, int] = {"benchmarks": 1}
    rows = []
    for level, title, command in sections(body):
        anchor = slug(title, seen)
        if level <= 3:
            rows.append(
                f"| {'&nbsp;' * 4 * (level - 2)}[{re.sub(r'[`|]', '', title)}](#{anchor}) | "
                f"{f'`{command}`' if command else 'see the section'} |"
            )
    index = [
        "# Benchmarks",
        "",
        "The figures below are `BENCHMARKS.md` of the repository, as the benchmark scripts last",
        "wrote it; each section says how it was made and on what machine. Rerun a section with the",
        "command next to it (`make compare` reruns the first ones, `make bench` the criterion",
        "benchmarks).",
        "",
        "| section | written by |",
        "|---|---|",
        *rows,
        "",
    ]
    return "\n".join(index) + body


def on_files(files, config):
    root = Path(config["config_file_path"]).parent
    files.append(File.generated(config, PAGE, content=page(root)))
    return files
