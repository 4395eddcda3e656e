"""`python -m experiments.paper [--quick]`: reproduce the paper's figures (see reproduce.py)."""

import sys

from experiments.paper.reproduce import main

sys.exit(main())
