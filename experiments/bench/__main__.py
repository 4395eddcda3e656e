"""`python -m experiments.bench` (make bench): print every speed and memory figure."""

import sys

from experiments.bench.figures import main

sys.exit(main())
