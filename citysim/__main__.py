"""`python -m citysim ...` is the same as the `citysim` command."""

import sys

from citysim.cli import main

sys.exit(main())
