"""The stub ``_core.pyi`` carries the compiled module's docstrings word for word (IDEs show the
stub), as ``tests/stubs.py`` writes them."""

from __future__ import annotations

import ast
import importlib.util
import inspect
from pathlib import Path
from types import ModuleType, SimpleNamespace

from inexact_loops import _core

_SCRIPT = Path(__file__).resolve().parents[1] / "stubs.py"


def _stubs() -> ModuleType:
    spec = importlib.util.spec_from_file_location("stubs", _SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


stubs = _stubs()


def test_stub_docstrings_equal_the_modules() -> None:
    found = stubs.mismatches(stubs.STUB.read_text(encoding="utf-8"), _core)
    assert not found, (
        f"the docstrings of {', '.join(found)} in _core.pyi differ from the compiled module's: "
        "run `python tests/stubs.py` (after `pip install .`) to copy them"
    )


def test_every_documented_name_of_the_module_is_checked() -> None:
    tree = ast.parse(stubs.STUB.read_text(encoding="utf-8"))
    checked = {item.name for item in stubs.items(tree, _core)}
    documented = set()
    for name in _core.__all__:
        obj = getattr(_core, name)
        if not (inspect.isclass(obj) or callable(obj)):
            continue
        documented.add(name)
        if inspect.isclass(obj):
            for member, value in vars(obj).items():
                # A constant (an int, a str) carries its type's docstring, not one of its own.
                constant = isinstance(value, (int, float, str))
                if not member.startswith("_") and not constant and getattr(value, "__doc__", None):
                    documented.add(f"{name}.{member}")
    assert documented <= checked, sorted(documented - checked)


class _Fake:
    """A fake class.

    With a second paragraph and a backslash \\ and "quotes"."""

    @property
    def size(self) -> int:
        """Size, cells."""
        return 0

    @staticmethod
    def build() -> None:
        """Builds one."""


def test_the_generator_copies_replaces_and_adds_docstrings() -> None:
    module = SimpleNamespace(Fake=_Fake, helper=lambda: None)
    module.helper.__doc__ = "Helps.\n\nArgs:\n    x: a thing."
    stub = (
        "class Fake:\n"
        '    """Old."""\n'
        "\n"
        "    @property\n"
        "    def size(self) -> int: ...\n"
        "    @staticmethod\n"
        "    def build() -> None:\n"
        '        """Old too."""\n'
        "\n"
        "def helper() -> None: ...\n"
    )
    assert stubs.mismatches(stub, module) == ["Fake", "Fake.size", "Fake.build", "helper"]
    new = stubs.regenerate(stub, module)
    assert stubs.mismatches(new, module) == []
    assert stubs.regenerate(new, module) == new
    assert '    def size(self) -> int:\n        """Size, cells."""\n' in new
    assert (
        'def helper() -> None:\n    """Helps.\n\n    Args:\n        x: a thing.\n    """\n' in new
    )
