"""``python -m orbits.cli``: the same command line as the ``orbits`` script."""

import sys

from . import main

sys.exit(main())
