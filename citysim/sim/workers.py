"""Worker processes that end with the process that started them.

``citysim run``, ``calibrate`` and ``year`` run nights in pools of spawned processes. When the
command is stopped by a signal it cannot catch (SIGKILL) or does not handle (SIGTERM from a job
scheduler, ``kill``), the pool never shuts down and its workers would go on simulating, a full
night of CPU for nobody (seen: a killed comparison's worker ran on for half an hour). Each
worker therefore watches its parent from a daemon thread and exits as soon as the parent is
gone (the kernel re-parents an orphan, so its parent pid changes).
"""

from __future__ import annotations

import multiprocessing as mp
import os
import threading
import time
from concurrent.futures import ProcessPoolExecutor

#: How often a worker looks whether its parent is still there, s.
PARENT_CHECK_S = 0.5


def exit_with_parent(parent_pid: int, check_s: float = PARENT_CHECK_S) -> None:
    """Pool initializer: end this worker (exit code 1) once ``parent_pid`` is no longer its parent."""

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(check_s)
        os._exit(1)  # no clean-up to run: the results have nobody to go to

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


def spawn_pool(max_workers: int) -> ProcessPoolExecutor:
    """A pool of fresh interpreters (spawn: no forked OpenCV or pymunk state) that end with this process."""
    return ProcessPoolExecutor(max_workers=max_workers, mp_context=mp.get_context("spawn"),
                               initializer=exit_with_parent, initargs=(os.getpid(),))  # fmt: skip
