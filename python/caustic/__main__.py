"""``python -m caustic ARGS...``: the caustic command line (``caustic render``, ``merge``, ``farm``,
``bench``), the same program as the ``caustic`` binary."""

import sys

from . import main

if __name__ == "__main__":
    sys.exit(main())
