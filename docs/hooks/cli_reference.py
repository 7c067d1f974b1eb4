"""MkDocs hook: the command-line reference, generated at build time from the commands' own
argument definitions (their ``--help``), so it cannot fall behind the code.

``loops`` is the wheel's command (the same Rust code as the ``loops`` binary, run in-process by
``python -m inexact_loops._cli``); its ``--help`` lists the subcommands, and each subcommand's
``--help`` its arguments and options, which become a section per command with a table of options.
``loops-eval`` and ``loops-dask`` (Python's argparse) are shown as their help text. The page is
``reference/cli.md``; :func:`commands` and :func:`options` are what ``tests/test_docs.py``
compares the built page with.
"""

from __future__ import annotations

import html
import re
import subprocess
import sys

from mkdocs.structure.files import File

PAGE = "reference/cli.md"
OPTION = re.compile(r"^  (?:(-\w), )?\s*(--[\w-]+)(?: <([^>]+)>)?(?:\s{2,}(.*))?$")
ARGUMENT = re.compile(r"^  (<[^>]+>(?:\.\.\.)?|\[[^\]]+\](?:\.\.\.)?)(?:\s{2,}(.*))?$")


def help_text(*args: str, module: str = "inexact_loops._cli") -> str:
    """The help a command prints (``python -m MODULE ARGS --help``), in this interpreter."""
    done = subprocess.run(
        [sys.executable, "-m", module, *args, "--help"],
        capture_output=True,
        text=True,
        check=True,
        env={"COLUMNS": "100", "NO_COLOR": "1", **_env()},
    )
    return done.stdout


def _env() -> dict[str, str]:
    import os

    return dict(os.environ)


def commands() -> list[tuple[str, str]]:
    """The subcommands of ``loops`` (name, one-line summary), as its ``--help`` lists them."""
    text = help_text()
    block = text.split("\nCommands:\n", 1)[1].split("\n\n", 1)[0]
    found = []
    for line in block.splitlines():
        name, _, summary = line.strip().partition(" ")
        if name and name != "help":
            found.append((name, summary.strip()))
    return found


def parse(text: str) -> dict:
    """A clap help text as its parts: summary, usage, arguments, options and the rest."""
    lines = text.splitlines()
    parts: dict = {"summary": [], "usage": "", "arguments": [], "options": [], "after": []}
    section = "summary"
    for line in lines:
        if line.startswith("Usage: "):
            parts["usage"], section = line[len("Usage: ") :], "usage"
        elif line in ("Arguments:", "Options:"):
            section = line[:-1].lower()
        elif line and not line.startswith(" ") and section in ("options", "arguments"):
            section = "after"
            parts["after"].append(line)
        elif section == "summary":
            parts["summary"].append(line)
        elif section in ("options", "arguments"):
            entries = parts[section]
            pattern = OPTION if section == "options" else ARGUMENT
            matched = pattern.match(line)
            if matched and not line.startswith("      " * 2):
                if section == "options":
                    short, long, value, description = matched.groups()
                    entries.append([short, long, value, description or ""])
                else:
                    entries.append([None, matched.group(1), None, matched.group(2) or ""])
            elif entries and line.strip():
                entries[-1][3] = (entries[-1][3] + " " + line.strip()).strip()
        elif section == "after":
            parts["after"].append(line)
    return parts


def options(text: str) -> list[str]:
    """The long options of a clap help text (``--gamma``, ...)."""
    return [entry[1] for entry in parse(text)["options"]]


def _cell(text: str) -> str:
    return html.escape(text).replace("|", "\\|").replace("[", "\\[").replace("]", "\\]")


def _command_section(name: str, text: str) -> list[str]:
    parts = parse(text)
    out = [f"## `loops {name}`", "", " ".join(line.strip() for line in parts["summary"]).strip()]
    out += ["", "```text", f"{parts['usage']}", "```", ""]
    if parts["arguments"]:
        out += ["| argument | meaning |", "|---|---|"]
        out += [f"| `{a[1]}` | {_cell(a[3])} |" for a in parts["arguments"]]
        out.append("")
    if parts["options"]:
        out += ["| option | meaning |", "|---|---|"]
        for short, long, value, description in parts["options"]:
            flag = f"{short}, {long}" if short else long
            flag += f" <{value}>" if value else ""
            out.append(f"| `{flag}` | {_cell(description)} |")
        out.append("")
    after = "\n".join(parts["after"]).strip()
    if after:
        out += ["```text", after, "```", ""]
    return out


def page() -> str:
    """The whole reference page, as Markdown."""
    out = [
        "# Command line",
        "",
        "Generated when the site is built, from the commands' own `--help` (their argument",
        "definitions in `crates/loops-cli` and the Python console scripts): every command and",
        "every option is here, as the installed `loops` prints it. `loops <command> --help`",
        "prints the same on a terminal.",
        "",
        "| command | what it does |",
        "|---|---|",
    ]
    listed = commands()
    out += [f"| [`loops {n}`](#loops-{n}) | {_cell(s)} |" for n, s in listed]
    out += [
        "| [`loops-eval`](#loops-eval) | pose-graph evaluation of the samplers (`maps` extra) |",
        "| [`loops-dask`](#loops-dask) | a fleet from tiles, here or on a Dask cluster |",
        "",
    ]
    for name, _ in listed:
        out += _command_section(name, help_text(name))
    scripts = (("loops-eval", "inexact_loops.evaluate"), ("loops-dask", "inexact_loops.dask"))
    for name, module in scripts:
        out += [f"## `{name}`", "", "```text", help_text(module=module).rstrip(), "```", ""]
    return "\n".join(out) + "\n"


def on_files(files, config):
    files.append(File.generated(config, PAGE, content=page()))
    return files
