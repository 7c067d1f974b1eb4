"""Module order of the Rust crates: no cycles among a crate's top-level modules.

A crate's top-level modules are the files and folders of its ``src/`` (``lib.rs`` and
``main.rs`` are the root, not a module). Module ``a`` imports module ``b`` when code of ``a``
(outside its inline ``#[cfg(test)] mod tests``) names ``crate::b``, directly or inside a
``use crate::{...}`` group. A cycle means two concepts are not in an order, which is the
one rule of ARCHITECTURE.md for the crates' modules.

Run as a script to list every crate's module imports in dependency order::

    python tests/test_module_order.py            # every crate
    python tests/test_module_order.py loops-core # one
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

CRATES = Path(__file__).resolve().parent.parent / "crates"

_TESTS = re.compile(r"#\[cfg\(test\)\]\s*mod tests\s*\{")
_PATH = re.compile(r"\bcrate::(\w+)")
_GROUP = re.compile(r"\bcrate::\{")


def _without_tests(text: str) -> str:
    """The text before an inline test module (always the last item of a file here)."""
    found = _TESTS.search(text)
    return text[: found.start()] if found else text


def _group_names(text: str, start: int) -> list[str]:
    """First path segments of the entries of the brace group opening at ``text[start]``:
    ``{error::{Error, Result}, metric::Metric, trajectory}`` names error, metric, trajectory."""
    entries = _flatten_group(text, start).split(",")
    return [first for entry in entries if (first := re.split(r"\W", entry.strip(), maxsplit=1)[0])]


def _flatten_group(text: str, start: int) -> str:
    """The group's text at depth one only (nested groups removed)."""
    depth, out = 0, []
    for k in range(start, len(text)):
        ch = text[k]
        if ch == "{":
            depth += 1
            continue
        if ch == "}":
            depth -= 1
            if depth == 0:
                break
            continue
        if depth == 1:
            out.append(ch)
    return "".join(out)


def modules(crate: str) -> dict[str, list[Path]]:
    """Top-level module name -> its source files."""
    src = CRATES / crate / "src"
    found: dict[str, list[Path]] = {}
    for path in sorted(src.rglob("*.rs")):
        top = path.relative_to(src).parts[0]
        name = top.removesuffix(".rs")
        if name in ("lib", "main"):
            continue
        found.setdefault(name, []).append(path)
    return found


def imports(crate: str) -> dict[str, set[str]]:
    """Module -> the crate's modules it names."""
    mods = modules(crate)
    graph: dict[str, set[str]] = {name: set() for name in mods}
    for name, paths in mods.items():
        for path in paths:
            text = _without_tests(path.read_text(encoding="utf-8"))
            named = set(_PATH.findall(text))
            for group in _GROUP.finditer(text):
                named.update(_group_names(text, group.end() - 1))
            graph[name].update(m for m in named if m in graph and m != name)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def dependency_order(graph: dict[str, set[str]]) -> list[str]:
    """Modules with every module before those that import it (ties by name)."""
    order: list[str] = []
    placed: set[str] = set()
    while len(order) < len(graph):
        ready = sorted(m for m in graph if m not in placed and graph[m] <= placed)
        if not ready:  # a cycle: place the rest by name so the listing still shows them
            ready = sorted(m for m in graph if m not in placed)
        order.extend(ready)
        placed.update(ready)
    return order


def listing(crate: str) -> str:
    graph = imports(crate)
    lines = [f"{crate}:"]
    for name in dependency_order(graph):
        uses = ", ".join(sorted(graph[name])) or "-"
        lines.append(f"  {name:<16} uses {uses}")
    for group in cycles(graph):
        lines.append(f"  cycle among {', '.join(group)}")
    return "\n".join(lines)


ALL_CRATES = ("loops-core", "loops-io", "loops-py", "loops-cli", "loops-capi")


@pytest.mark.parametrize("crate", ALL_CRATES)
def test_modules_form_no_cycle(crate: str) -> None:
    found = cycles(imports(crate))
    assert not found, f"module cycles in {crate}:\n{listing(crate)}"


def test_a_cycle_is_found() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(graph) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_use_groups_name_their_first_segment() -> None:
    text = "use crate::{error::{Error, Result}, metric::Metric, trajectory};\nfn f() {}"
    assert _group_names(text, text.index("{")) == ["error", "metric", "trajectory"]


def test_inline_tests_do_not_count() -> None:
    text = "use crate::a::X;\n#[cfg(test)]\nmod tests {\n    use crate::b::Y;\n}\n"
    assert _PATH.findall(_without_tests(text)) == ["a"]


if __name__ == "__main__":
    chosen = sys.argv[1:] or list(ALL_CRATES)
    reports = [listing(crate) for crate in chosen]
    print("\n".join(reports))
    sys.exit(1 if any("cycle among" in r for r in reports) else 0)
