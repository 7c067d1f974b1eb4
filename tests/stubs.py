"""The docstrings of ``python/inexact_loops/_core.pyi``, copied from the compiled module.

IDEs show the stub, not the bindings, so the stub carries the bindings' docstrings word for
word: every class, public method, property and function of ``inexact_loops._core`` (names
starting with ``_`` and the module docstring are the stub's own). Signatures and types stay
as written in the stub; only docstrings are rewritten.

Usage, with the package built and installed (``pip install .``)::

    python tests/stubs.py          # rewrite the stub's docstrings from the installed module
    python tests/stubs.py --check  # list the docstrings that differ; exit 1 if any

``tests/python/test_stubs.py`` runs the check.
"""

from __future__ import annotations

import ast
import inspect
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import NamedTuple

STUB = Path(__file__).resolve().parent.parent / "python" / "inexact_loops" / "_core.pyi"

_Def = ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef


class Item(NamedTuple):
    """A documented definition of the stub and the runtime object it describes."""

    name: str  # "Loops.gamma"
    node: _Def
    runtime_doc: str | None  # cleaned as IDEs show it, or None when the binding has none


def _runtime_doc(obj: object) -> str | None:
    doc = getattr(obj, "__doc__", None)
    return inspect.cleandoc(doc) if isinstance(doc, str) and doc.strip() else None


def _later_overloads(body: list[ast.stmt]) -> set[int]:
    """The ``@overload`` signatures of ``body`` (by ``id``) that another def of the same name
    follows: the last one carries the docstring (a stub has no implementation)."""
    last: dict[str, ast.stmt] = {}
    for node in body:
        if isinstance(node, _Def):
            last[node.name] = node
    return {
        id(node)
        for node in body
        if isinstance(node, _Def)
        and last[node.name] is not node
        and any(isinstance(d, ast.Name) and d.id == "overload" for d in node.decorator_list)
    }


def items(tree: ast.Module, module: ModuleType) -> Iterator[Item]:
    """The stub's public classes, functions, methods and properties that the module has (of
    ``@overload`` signatures, the last: it carries the docstring)."""
    skipped = _later_overloads(tree.body)
    for node in tree.body:
        if not isinstance(node, _Def) or node.name.startswith("_") or id(node) in skipped:
            continue
        obj = getattr(module, node.name, None)
        if obj is None:
            continue  # mypy.stubtest reports it
        yield Item(node.name, node, _runtime_doc(obj))
        if isinstance(node, ast.ClassDef):
            later = _later_overloads(node.body)
            for member in node.body:
                if (
                    not isinstance(member, _Def)
                    or member.name.startswith("_")
                    or id(member) in later
                ):
                    continue
                if member.name in vars(obj):  # its own, not inherited from object
                    runtime = getattr(obj, member.name)  # a static method's function
                    yield Item(f"{node.name}.{member.name}", member, _runtime_doc(runtime))


def mismatches(stub_text: str, module: ModuleType) -> list[str]:
    """The names whose stub docstring differs from the module's (both cleaned)."""
    tree = ast.parse(stub_text)
    return [
        item.name
        for item in items(tree, module)
        if ast.get_docstring(item.node, clean=True) != item.runtime_doc
    ]


def _literal(doc: str, indent: str) -> str:
    """``doc`` as a triple-quoted string in a block indented by ``indent``."""
    text = doc.replace("\\", "\\\\").replace('"""', '\\"""')
    if text.endswith('"'):
        text += " "
    lines = text.split("\n")
    if len(lines) == 1:
        return f'"""{text}"""'
    body = "\n".join(f"{indent}{line}" if line else "" for line in lines[1:])
    return f'"""{lines[0]}\n{body}\n{indent}"""'


def _offsets(text: str) -> list[int]:
    """Offset of the start of each line (1-based line numbers index it after a 0 entry)."""
    starts = [0, 0]
    for line in text.splitlines(keepends=True):
        starts.append(starts[-1] + len(line))
    return starts


def regenerate(stub_text: str, module: ModuleType) -> str:
    """The stub with every docstring of :func:`items` replaced by the module's."""
    tree = ast.parse(stub_text)
    line_start = _offsets(stub_text)

    def at(line: int, column: int) -> int:
        # ast columns count UTF-8 bytes.
        start = line_start[line]
        end = line_start[line + 1] if line + 1 < len(line_start) else len(stub_text)
        prefix = stub_text[start:end].encode("utf-8")[:column]
        return start + len(prefix.decode("utf-8"))

    edits: list[tuple[int, int, str]] = []
    for item in items(tree, module):
        if ast.get_docstring(item.node, clean=True) == item.runtime_doc:
            continue
        first = item.node.body[0]
        has_doc = (
            isinstance(first, ast.Expr)
            and isinstance(first.value, ast.Constant)
            and isinstance(first.value.value, str)
        )
        assert first.end_lineno is not None and first.end_col_offset is not None
        start = at(first.lineno, first.col_offset)
        end = at(first.end_lineno, first.end_col_offset)
        lone = len(item.node.body) == 1
        if has_doc and item.runtime_doc is not None:
            new = _literal(item.runtime_doc, " " * first.col_offset)
        elif has_doc:
            if not lone:
                raise SystemExit(f"{item.name} has no docstring in the module: remove the stub's")
            new = "..."
        elif lone and isinstance(first, ast.Expr) and ast.unparse(first) == "...":
            # ``def f() -> int: ...``: the docstring replaces the ``...``, on its own line.
            indent = " " * (item.node.col_offset + 4)
            start = stub_text.rindex(":", 0, start) + 1
            new = f"\n{indent}{_literal(item.runtime_doc or '', indent)}"
        else:
            indent = " " * first.col_offset
            new = f"{_literal(item.runtime_doc or '', indent)}\n{indent}"
            end = start
        edits.append((start, end, new))
    for start, end, new in sorted(edits, reverse=True):
        stub_text = stub_text[:start] + new + stub_text[end:]
    return stub_text


def main(argv: list[str]) -> int:
    from inexact_loops import _core

    text = STUB.read_text(encoding="utf-8")
    if argv == ["--check"]:
        found = mismatches(text, _core)
        for name in found:
            print(f"{STUB.name}: the docstring of {name} differs from the compiled module's")
        if found:
            print("run `python tests/stubs.py` (after `pip install .`) to copy them")
        return 1 if found else 0
    if argv:
        print(__doc__)
        return 2
    new = regenerate(text, _core)
    left = mismatches(new, _core)
    if left:
        raise SystemExit(f"could not copy the docstrings of {', '.join(left)}")
    if new != text:
        STUB.write_text(new, encoding="utf-8")
        print(f"rewrote {STUB}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
