"""``python -m gearmodal``: the command line (:mod:`gearmodal.cli`)."""

import sys

from .cli import main

sys.exit(main())
