"""What the console scripts written in Python (``loops-eval``, ``loops-dask``) share with the
``loops`` command: a usage error is one line on stderr with exit code 2, naming the option and
value and where the help is; Ctrl-C exits with code 130 and one line, never a traceback."""

from __future__ import annotations

import argparse
import sys
from typing import NoReturn

#: The exit code of a run stopped by Ctrl-C (128 + SIGINT), as ``loops`` returns it.
INTERRUPTED = 130


class ArgumentParser(argparse.ArgumentParser):
    """:class:`argparse.ArgumentParser` whose usage errors are one line:
    ``PROG: error: MESSAGE (try 'PROG --help')``, exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (try '{self.prog} --help')\n")


def interrupted(prog: str) -> int:
    """Reports Ctrl-C in one line; returns the exit code."""
    print(f"{prog}: interrupted", file=sys.stderr)
    return INTERRUPTED
