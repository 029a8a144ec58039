"""``python -m curved_fold``: the headless command line (see :mod:`.cli`)."""

import sys

from .cli import main

sys.exit(main())
