"""``python -m emaphm``: the command line (:func:`emaphm.cli.main`), as the ``emaphm``
script runs it."""

import sys

from .cli import main

sys.exit(main())
