"""Set-up shared by every test process."""

from __future__ import annotations

import signal

# A test run started in the background (`make test &`, `nohup .ci/run &` from a non-interactive
# shell) inherits SIGINT ignored, and so would every process a test starts: the tests that press
# Ctrl-C, in this process or in a real `citysim` child, would then test nothing. They test what a
# user at a terminal gets, so Ctrl-C is given back its interactive meaning here (a child process
# gets the default action, on which Python installs its KeyboardInterrupt handler).
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)
