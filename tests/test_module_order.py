"""Module order of the Rust crates and of the Python package: no cycles, layers import downward.

A crate's top-level modules are the files and folders of its ``src/`` (``lib.rs`` and
``main.rs`` are the root, not a module). Module ``a`` imports module ``b`` when code of ``a``
(outside its inline ``#[cfg(test)] mod tests``) names ``crate::b``, directly or inside a
``use crate::{...}`` group (comment lines, doc links included, are not code). A cycle means
two concepts are not in an order, which is the one rule of ARCHITECTURE.md for the crates'
modules. The parts of a folder module (``tile/draw.rs``, ``cluster/grid.rs``) are held to it
too, among themselves: part ``a`` imports part ``b`` when it names ``super::b`` or
``crate::<folder>::b``.

The Python package ``python/inexact_loops`` is held to the same rule, module by module
(``inexact_loops.evaluate._poses``, a package by its ``__init__``): module ``a`` imports ``b``
when ``a`` has an import statement naming ``b`` anywhere in it -- at the top, under
``TYPE_CHECKING`` or inside a function, since a lazy import is still a dependency. Besides no
cycle, its layers import only downward: a package's ``__init__`` serves the names of its parts,
so no part imports its own package or one above it.

Run as a script to list every crate's module imports in dependency order::

    python tests/test_module_order.py               # every crate and the Python package
    python tests/test_module_order.py loops-core    # one
    python tests/test_module_order.py inexact_loops # the Python package
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import pytest

CRATES = Path(__file__).resolve().parent.parent / "crates"
PYTHON = Path(__file__).resolve().parent.parent / "python"
PACKAGE = "inexact_loops"

_TESTS = re.compile(r"#\[cfg\(test\)\]\s*mod tests\s*\{")
_PATH = re.compile(r"\bcrate::(\w+)")
_GROUP = re.compile(r"\bcrate::\{")
_COMMENT = re.compile(r"^[ \t]*//.*$", re.M)


def _without_tests(text: str) -> str:
    """The code before an inline test module (always the last item of a file here), without
    its comment lines: a doc link to a later module (``[`OnlineLoops`](crate::online::...)``
    in ``error``) names it for the reader, and is no import."""
    found = _TESTS.search(text)
    return _COMMENT.sub("", text[: found.start()] if found else text)


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


def folder_modules(crate: str) -> dict[str, dict[str, Path]]:
    """Folder module -> its parts: the files of ``src/<folder>/`` other than ``mod.rs`` (the
    folder's root, as ``lib.rs`` is the crate's)."""
    src = CRATES / crate / "src"
    return {
        folder.name: {path.stem: path for path in sorted(folder.glob("*.rs")) if path.stem != "mod"}
        for folder in sorted(p for p in src.iterdir() if p.is_dir())
    }


def part_imports(crate: str, folder: str) -> dict[str, set[str]]:
    """Part of a folder module -> the parts of the same folder it names: ``super::b``,
    ``crate::<folder>::b``, or inside a ``use super::{...}`` group."""
    parts = folder_modules(crate)[folder]
    paths = re.compile(rf"\b(?:super|crate::{folder})::(\w+)")
    groups = re.compile(rf"\b(?:super|crate::{folder})::\{{")
    graph: dict[str, set[str]] = {name: set() for name in parts}
    for name, path in parts.items():
        text = _without_tests(path.read_text(encoding="utf-8"))
        named = set(paths.findall(text))
        for group in groups.finditer(text):
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


def python_modules(root: Path = PYTHON, package: str = PACKAGE) -> dict[str, Path]:
    """Dotted module name -> its file, for every module of ``package`` under ``root`` (a
    package by its ``__init__.py``; a compiled module by its ``.pyi`` stub)."""
    found: dict[str, Path] = {}
    for path in sorted((root / package).rglob("*.py*")):
        if path.suffix not in (".py", ".pyi") or "__pycache__" in path.parts:
            continue
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        elif parts[-1] == "__main__":
            continue  # runs the package's command line: above everything, imported by none
        found.setdefault(".".join(parts), path)
    return found


def _imported(module: str, is_package: bool, node: ast.AST, known: set[str]) -> set[str]:
    """The package's modules that one import statement of ``module`` names."""
    if isinstance(node, ast.Import):
        targets = [alias.name for alias in node.names]
    elif isinstance(node, ast.ImportFrom):
        if node.level:
            base = module.split(".")
            base = base[: len(base) - node.level + (1 if is_package else 0)]
            stem = ".".join(base + ([node.module] if node.module else []))
        else:
            stem = node.module or ""
        submodules = [f"{stem}.{alias.name}" for alias in node.names]
        # ``from . import x`` of a module x does not use the package's own names
        uses_stem = any(sub not in known for sub in submodules)
        targets = ([stem] if uses_stem else []) + submodules
    else:
        return set()
    named = set()
    for target in targets:
        # the longest known module that the target is or lies in (a name of a module counts
        # as its module)
        parts = target.split(".")
        for k in range(len(parts), 0, -1):
            if (candidate := ".".join(parts[:k])) in known:
                named.add(candidate)
                break
    return named


def python_imports(root: Path = PYTHON, package: str = PACKAGE) -> dict[str, set[str]]:
    """Module -> the package's modules it imports (anywhere in its file)."""
    mods = python_modules(root, package)
    known = set(mods)
    graph: dict[str, set[str]] = {name: set() for name in mods}
    for name, path in mods.items():
        is_package = path.stem == "__init__"
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            for target in _imported(name, is_package, node, known):
                if target != name:
                    graph[name].add(target)
    return graph


def upward_imports(graph: dict[str, set[str]]) -> list[str]:
    """``a -> p`` for every module ``a`` that imports its own package ``p`` or one above it."""
    return sorted(
        f"{name} -> {target}"
        for name, targets in graph.items()
        for target in targets
        if name.startswith(target + ".")
    )


def python_listing(root: Path = PYTHON, package: str = PACKAGE) -> str:
    graph = python_imports(root, package)
    lines = [f"{package}:"]
    for name in dependency_order(graph):
        uses = ", ".join(sorted(graph[name])) or "-"
        lines.append(f"  {name:<36} uses {uses}")
    for group in cycles(graph):
        lines.append(f"  cycle among {', '.join(group)}")
    for edge in upward_imports(graph):
        lines.append(f"  upward import {edge}")
    return "\n".join(lines)


def test_python_modules_form_no_cycle() -> None:
    graph = python_imports()
    assert f"{PACKAGE}.evaluate._fleet" in graph, "the package's modules were not found"
    found = cycles(graph)
    assert not found, f"module cycles in {PACKAGE}:\n{python_listing()}"


def test_python_layers_import_only_downward() -> None:
    found = upward_imports(python_imports())
    assert not found, f"modules importing their own package:\n{python_listing()}"


def test_python_imports_count_lazy_and_relative_ones(tmp_path: Path) -> None:
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from .sub import thing\n")
    (pkg / "_core.pyi").write_text("def f() -> None: ...\n")
    (pkg / "base.py").write_text("from ._core import f\n")
    (pkg / "sub" / "__init__.py").write_text("from .a import thing\n")
    (pkg / "sub" / "a.py").write_text("from .. import base\ndef g():\n    from . import b\n")
    (pkg / "sub" / "b.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .a import thing\n"
    )
    graph = python_imports(tmp_path, "pkg")
    assert graph == {
        "pkg": {"pkg.sub"},
        "pkg._core": set(),
        "pkg.base": {"pkg._core"},
        "pkg.sub": {"pkg.sub.a"},
        "pkg.sub.a": {"pkg.base", "pkg.sub.b"},
        "pkg.sub.b": {"pkg.sub.a"},
    }
    assert cycles(graph) == [["pkg.sub.a", "pkg.sub.b"]]
    (pkg / "sub" / "b.py").write_text("from . import thing\n")  # the package's own name
    assert upward_imports(python_imports(tmp_path, "pkg")) == ["pkg.sub.b -> pkg.sub"]


@pytest.mark.parametrize("crate", ALL_CRATES)
def test_modules_form_no_cycle(crate: str) -> None:
    found = cycles(imports(crate))
    assert not found, f"module cycles in {crate}:\n{listing(crate)}"


@pytest.mark.parametrize("crate", ALL_CRATES)
def test_the_parts_of_folder_modules_form_no_cycle(crate: str) -> None:
    found = {
        folder: cycles(part_imports(crate, folder))
        for folder in folder_modules(crate)
        if cycles(part_imports(crate, folder))
    }
    assert not found, f"cycles among the parts of folder modules of {crate}: {found}"


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


def test_doc_links_do_not_count() -> None:
    text = "/// See [`Y`](crate::b::Y).\n//! [`c`]: crate::c\nfn f() -> crate::a::X { todo!() }\n"
    assert _PATH.findall(_without_tests(text)) == ["a"]


if __name__ == "__main__":
    chosen = sys.argv[1:] or [*ALL_CRATES, PACKAGE]
    reports = [python_listing() if name == PACKAGE else listing(name) for name in chosen]
    print("\n".join(reports))
    sys.exit(1 if any("cycle among" in r or "upward import" in r for r in reports) else 0)
