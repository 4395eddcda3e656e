"""Worker processes that end with the process that started them, or when it stops waiting for them.

``citysim run``, ``calibrate`` and ``year`` run nights in pools of spawned processes. Two ways a
pool's workers could go on simulating for nobody (seen: a killed comparison's worker ran on for
half an hour):

* the command dies without a word (SIGKILL): each worker watches its parent from a daemon
  thread and exits as soon as the parent is gone (the kernel re-parents an orphan, so its
  parent pid changes);
* the command is stopped in an orderly way (an error, Ctrl-C, SIGTERM turned into an exit by
  ``detector.outdir.exit_on_terminate``): leaving the ``spawn_pool`` block by an exception sets
  the pool's stop event, which the same thread watches, and waits only for the workers to exit
  (half a second), not for the running nights to finish (what ``ProcessPoolExecutor``'s own
  exit does), so the command's clean-up runs at once.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

#: How often a worker looks whether its parent is still there, s.
PARENT_CHECK_S = 0.5


class WorkerLost(RuntimeError):
    """A worker process ended in the middle of its task (killed, or out of memory); the message
    names what it was running."""


def exit_with_parent(parent_pid: int, stop=None, check_s: float = PARENT_CHECK_S) -> None:
    """Pool initializer: end this worker (exit code 1) once ``parent_pid`` is no longer its parent
    or the ``stop`` event (a ``multiprocessing`` Event) is set.

    Ctrl-C reaches every process of the terminal's group: a worker ignores it (it would print a
    traceback of its own) and leaves the stopping to its parent, which sets ``stop``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    stop = stop if stop is not None else threading.Event()  # a local one that nobody sets

    def watch() -> None:
        while os.getppid() == parent_pid and not stop.wait(check_s):
            pass
        os._exit(1)  # no clean-up to run: the results have nobody to go to

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


@contextmanager
def spawn_pool(max_workers: int) -> Iterator[ProcessPoolExecutor]:
    """A pool of fresh interpreters (spawn: no forked OpenCV or pymunk state) that end with this
    process, and at once when the block is left by an exception (see the module docstring)."""
    context = mp.get_context("spawn")
    stop = context.Event()
    pool = ProcessPoolExecutor(max_workers=max_workers, mp_context=context,
                               initializer=exit_with_parent, initargs=(os.getpid(), stop))  # fmt: skip
    try:
        yield pool
    except BaseException:
        stop.set()
        # the workers are gone within ``PARENT_CHECK_S``: waiting for that (not for their tasks)
        # keeps what they use, such as a progress queue's manager, alive until they are
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def worker_exits(pool: ProcessPoolExecutor) -> dict[int, int | None]:
    """The pool's worker processes by pid with their exit codes (None: still running; -N: ended
    by signal N), read from the executor's own table of them."""
    processes = getattr(pool, "_processes", None) or {}
    return {pid: process.exitcode for pid, process in dict(processes).items()}


def describe_exit(code: int | None) -> str:
    """'killed by SIGKILL', 'exit code 1', 'ended' (unknown) for a worker's exit code."""
    if code is None:
        return "ended"
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"
