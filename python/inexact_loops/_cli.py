"""The ``loops`` command of the wheel: the console script ``loops = "inexact_loops._cli:main"``.

It runs the command line of ``crates/loops-cli`` -- the same Rust code as the binary that
``cargo install --path crates/loops-cli`` builds, compiled into the extension module and called
through :func:`inexact_loops._core.run_cli` -- so ``pip install .`` compiles the workspace once
and gives both the library and the command, with the binary's output and exit codes (0; 1 when
a log of ``loops run`` failed; 2 on an error; 130 on Ctrl-C; 0 when stdout is closed early, as in
``loops demo | head``). A separate ``loops`` binary in the wheel would compile loops-core,
loops-io and the command a second time in every build; calling the command through the module
only adds the command's own code to it (docs/reference/python-behaviour.md gives the
figures). Its one cost is start-up: Python and numpy are imported before the command runs.

``python -m inexact_loops._cli ARGS`` runs it too.
"""

from __future__ import annotations

import sys

from ._core import run_cli


def main() -> int:
    """Runs ``loops`` with this process's arguments; returns its exit code."""
    return run_cli(sys.argv[1:])


if __name__ == "__main__":
    sys.exit(main())
