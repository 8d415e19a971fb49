"""``python -m orbits``: the same command line as the ``orbits`` script."""

import sys

from .cli import main

sys.exit(main())
