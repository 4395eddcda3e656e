"""Worker processes that end with the process that started them, or when it stops waiting for them.

``citysim run``, ``calibrate`` and ``year`` run nights in pools of spawned processes. Two ways a
pool's workers could go on simulating for nobody (seen: a killed comparison's worker ran on for
half an hour):

* the command dies without a word (SIGKILL): each worker watches its parent from a daemon
  thread and exits as soon as the parent is gone (the kernel re-parents an orphan, so its
  parent pid changes);
* the command is stopped in an orderly way (an error, Ctrl-C, SIGTERM turned into an exit by
  ``detector.outdir.stop_on_signals``): leaving the ``spawn_pool`` block by an exception sets
  the pool's stop flag, which the same thread reads, and waits only for the workers to exit
  (half a second), not for the running nights to finish (what ``ProcessPoolExecutor``'s own
  exit does), so the command's clean-up runs at once.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
import time
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
    or ``stop`` is set: a shared flag (``multiprocessing`` RawValue, non-zero to stop) or an
    object with ``is_set()``.

    The flag is read, never waited on: a ``multiprocessing.Event`` that a killed worker was waiting
    on makes the parent's ``set()`` wait forever for it to wake (seen: a run stopped by SIGTERM,
    sent to its whole process group, hung in ``Event.set``). Ctrl-C reaches every process of the
    terminal's group: a worker ignores it (it would print a traceback of its own) and leaves the
    stopping to its parent."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # tqdm's default lock is a multiprocessing semaphore, made by the first bar (even a disabled one);
    # a worker that leaves by os._exit never releases it and the resource tracker warns of a leak
    from tqdm import tqdm

    tqdm.set_lock(threading.RLock())
    if stop is None:
        stopped = lambda: False  # noqa: E731
    elif hasattr(stop, "is_set"):
        stopped = stop.is_set
    else:
        stopped = lambda: bool(stop.value)  # noqa: E731

    def watch() -> None:
        while os.getppid() == parent_pid and not stopped():
            time.sleep(check_s)
        os._exit(1)  # no clean-up to run: the results have nobody to go to

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


@contextmanager
def sigint_blocked() -> Iterator[None]:
    """Block Ctrl-C (SIGINT) in this thread for the block: processes and threads started within
    inherit the blocked mask and never see it (this process still does, in its main thread, once
    the block ends). For worker processes whose parent does the stopping."""
    old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)


@contextmanager
def sigint_ignored_by_children() -> Iterator[None]:
    """Processes started within the block, and theirs, ignore Ctrl-C (SIGINT) for good: the
    ignored disposition survives fork and exec, from whichever thread starts them (a Dask
    cluster's event loop). A Ctrl-C meanwhile is held, not lost: SIGINT is blocked in this
    thread too, and a blocked signal stays pending even while ignored; it is handled as the
    block ends."""
    with sigint_blocked():
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, previous)


class _QuietPool(ProcessPoolExecutor):
    """Starts its workers with Ctrl-C (SIGINT) blocked: a worker inherits the signal mask of the
    process that forked it, so a Ctrl-C during its second of interpreter start-up (before its
    initializer ignores SIGINT) stays pending and harmless instead of printing a traceback."""

    def submit(self, fn, /, *args, **kwargs):
        with sigint_blocked():
            return super().submit(fn, *args, **kwargs)


@contextmanager
def spawn_pool(max_workers: int) -> Iterator[ProcessPoolExecutor]:
    """A pool of fresh interpreters (spawn: no forked OpenCV or pymunk state) that end with this
    process, and at once when the block is left by an exception (see the module docstring)."""
    context = mp.get_context("spawn")
    stop = context.RawValue("b", 0)  # a flag in shared memory: setting it never waits on anyone
    pool = _QuietPool(max_workers=max_workers, mp_context=context,
                               initializer=exit_with_parent, initargs=(os.getpid(), stop))  # fmt: skip
    try:
        yield pool
    except BaseException:
        stop.value = 1
        # the workers are gone within ``PARENT_CHECK_S``: waiting for that (not for their tasks)
        # keeps what they use, such as a progress queue's manager, alive until they are
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def worker_processes(pool: ProcessPoolExecutor) -> dict[int, object]:
    """The pool's worker processes by pid (``multiprocessing`` Process objects), from the
    executor's own table of them; keep them: a broken pool clears its table."""
    return dict(getattr(pool, "_processes", None) or {})


def exit_codes(processes: dict[int, object], wait_s: float = 2.0) -> dict[int, int | None]:
    """Each process's exit code (-N: ended by signal N; None: still running after ``wait_s``)."""
    for process in processes.values():
        process.join(wait_s)
    return {pid: process.exitcode for pid, process in processes.items()}


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
