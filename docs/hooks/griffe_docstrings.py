"""A griffe extension for the API reference: the package's docstrings are written for Python's
``help()`` and for the compiled module's stub (reST roles such as :func:`find_loops`, an
``Example:`` section of doctests). Here the roles become code spans and ``Example:`` the Google
style's ``Examples:`` section, so that doctests render as code rather than as Markdown."""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:func|meth|class|attr|mod|data|exc|obj|const):`~?([^`]+)`")
EXAMPLE = re.compile(r"^(\s*)Example:\s*$", re.M)


class ReadableDocstrings(griffe.Extension):
    """Rewrites each docstring before it is parsed (see the module docstring)."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is None:
            return
        text = ROLE.sub(lambda m: f"``{m.group(1)}``", obj.docstring.value)
        obj.docstring.value = EXAMPLE.sub(r"\1Examples:", text)
