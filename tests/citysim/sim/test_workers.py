"""A pool's workers end with the process that started them, even one killed with SIGKILL."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

# a parent that starts a pool of two workers, each sleeping 60 s in a task, prints their pids and waits
PARENT = """
import os, sys, time
from citysim.sim.workers import spawn_pool

def task(_):
    time.sleep(60)

if __name__ == "__main__":
    pool = spawn_pool(2)
    for f in [pool.submit(task, i) for i in range(2)]:
        pass
    time.sleep(2.0)  # both workers started and busy
    print(" ".join(str(p) for p in pool._processes), flush=True)  # the pool's worker pids (CPython)
    time.sleep(60)
"""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie is dead but not yet reaped by its new parent
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(") ")[1][0] != "Z"
    except FileNotFoundError:
        return False


def test_workers_exit_once_their_parent_is_killed(tmp_path):
    script = tmp_path / "parent.py"
    script.write_text(PARENT)
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    try:
        workers = [int(p) for p in parent.stdout.readline().split()]
        assert len(workers) == 2 and all(_alive(p) for p in workers)
        os.kill(parent.pid, signal.SIGKILL)  # no handler, no pool shutdown
        parent.wait()
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline and any(_alive(p) for p in workers):
            time.sleep(0.1)
        assert not any(_alive(p) for p in workers), "a worker outlived its parent"
    finally:
        parent.kill()
