"""`python -m legged.cli ...`: the `legged` command."""

import sys

from legged.cli import main

if __name__ == "__main__":
    sys.exit(main())
