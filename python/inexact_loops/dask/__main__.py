"""``python -m inexact_loops.dask``: ``loops-dask``."""

import sys

from ._cli import main

sys.exit(main())
