"""``python -m inexact_loops.evaluate``: ``loops-eval``."""

import sys

from ._cli import main

sys.exit(main())
