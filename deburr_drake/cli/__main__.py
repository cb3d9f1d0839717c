"""``python -m deburr_drake.cli``."""

import sys

from deburr_drake.cli import main

if __name__ == "__main__":
    sys.exit(main())
