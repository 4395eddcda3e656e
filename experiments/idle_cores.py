"""Commands run one after another at the lowest CPU priority, behind the work in the foreground.

``make demo``'s night keeps both cores busy, but not all the time: for its first seconds one worker
waits for the traffic recorder (compiling the world's kernels), and for its last half minute one
worker has nothing left while the other finishes the camera controller. The check and the year
need neither the night's results nor its cores' full attention, so they run behind it at nice 19
(POSIX ``nice``): the kernel gives them the CPU time the night leaves idle (a nice-19 process gets
about 1.5 % of a core when it competes with a nice-0 one), and the night is not slowed. Each
command's output is kept and handed over whole once it has finished, so tables never interleave
with the foreground's progress bar.
"""

from __future__ import annotations

import contextlib
import os
import queue
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

#: POSIX ``nice``'s lowest priority: only otherwise idle CPU time, in practice
LOWEST_PRIORITY_NICE = 19


@dataclass(frozen=True)
class Finished:
    """One command's outcome: its exit code, everything it printed (stdout and stderr, in order),
    its wall seconds from start to end and the CPU seconds of it and its child processes."""

    title: str
    exit_code: int
    output: str
    wall_s: float
    cpu_s: float


def at_lowest_priority(argv: Sequence[str]) -> list[str]:
    """``argv`` run through POSIX ``nice`` at the lowest priority (unchanged where there is no ``nice``:
    then it competes with the foreground as an equal, slower but with the same results)."""
    nice = shutil.which("nice")
    return [nice, "-n", str(LOWEST_PRIORITY_NICE), *argv] if nice else list(argv)


class BehindChain:
    """Start ``commands`` ((title, argv) pairs) at once, in a thread, one after another at the lowest
    priority; ``finished()`` yields each outcome in order as it ends. A command that fails ends the
    chain (the ones after it do not start). ``stop()`` ends the running command and the chain."""

    def __init__(self, commands: Sequence[tuple[str, Sequence[str]]]):
        self._outcomes: queue.Queue[Finished | None] = queue.Queue()
        self._stopped = threading.Event()
        self._lock = threading.Lock()  # a command starts and stop() looks at it one at a time
        self._running: subprocess.Popen | None = None
        self.reaped_cpu_s = 0.0  # CPU seconds of the commands ended so far: they count in RUSAGE_CHILDREN
        self._thread = threading.Thread(target=self._run_all, args=(list(commands),), name="behind-chain", daemon=True)
        self._thread.start()

    def _run_all(self, commands: list[tuple[str, Sequence[str]]]) -> None:
        try:
            for title, argv in commands:
                outcome = self._run_one(title, argv)
                if outcome is None:  # stopped before it started
                    break
                self._outcomes.put(outcome)
                if outcome.exit_code:
                    break
        finally:
            self._outcomes.put(None)  # the end of the chain, also when a command could not start

    def _run_one(self, title: str, argv: Sequence[str]) -> Finished | None:
        with tempfile.TemporaryFile() as log:
            t0 = time.perf_counter()
            with self._lock:
                if self._stopped.is_set():
                    return None
                process = subprocess.Popen(at_lowest_priority(argv), stdin=subprocess.DEVNULL, stdout=log,
                                           stderr=subprocess.STDOUT)  # fmt: skip
                self._running = process
            # wait4, not wait(): the CPU seconds of this command and of the workers it waited for
            _, status, usage = os.wait4(process.pid, 0)
            process.returncode = exit_code = os.waitstatus_to_exitcode(status)
            self.reaped_cpu_s += usage.ru_utime + usage.ru_stime
            wall_s = time.perf_counter() - t0
            log.seek(0)
            output = log.read().decode(errors="replace")
        return Finished(title, exit_code, output, wall_s, usage.ru_utime + usage.ru_stime)

    def finished(self) -> Iterator[Finished]:
        """Each command's outcome in order, waiting for it to end."""
        while (outcome := self._outcomes.get()) is not None:
            yield outcome

    def stop(self) -> None:
        """End the running command (SIGTERM: its worker pools end with it) and start no other."""
        with self._lock:
            self._stopped.set()
            running = self._running
            if running is not None and running.returncode is None:
                # os.kill, not Popen.terminate: that polls, and a poll could reap the process under wait4
                with contextlib.suppress(ProcessLookupError):  # it ended this very moment
                    os.kill(running.pid, signal.SIGTERM)
        self._thread.join(timeout=10)
