"""``python -m deburr_drake.cli``."""

import sys

from deburr_drake.cli import main

sys.exit(main())
