"""Commands run beside and behind the work in the foreground, their output kept until it is done.

``make demo``'s night keeps both cores busy, but not all the time: for its first seconds one worker
waits for the traffic recorder (compiling the world's kernels), and for its last seconds one worker
has nothing left while the other finishes the camera controller. The check and the year need
nothing of the night, so they start with it:

* the year at nice 19 (POSIX ``nice``, the lowest priority): the kernel gives it only the CPU time
  the night leaves idle (a nice-19 process gets about 1.5 % of a core when it competes with a
  nice-0 one), so the night is not slowed;
* the check at the night's own priority: its ~40 CPU-s are one serial chain (the world's and then
  the renderer's and detector's kernels compiled, one worker rendering), which behind the night
  only ran once the night was done, alone on one core. Beside it, it shares both cores from the
  start: measured on a fresh clone's demo, the check beside and the year behind ended 122 and
  134 s after the start, both behind 152 and 154 s.

Each command's output is kept and handed over whole once it has finished, so tables never
interleave with the foreground's progress bar.
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


def at_priority(argv: Sequence[str], nice_level: int = LOWEST_PRIORITY_NICE) -> list[str]:
    """``argv`` run through POSIX ``nice`` at ``nice_level`` (0: unchanged, the foreground's own
    priority; unchanged too where there is no ``nice``: then it competes with the foreground as an
    equal, with the same results)."""
    nice = shutil.which("nice")
    return [nice, "-n", str(nice_level), *argv] if nice and nice_level else list(argv)


class BehindChain:
    """Start ``commands`` ((title, argv) pairs) at once, in a thread, one after another at
    ``nice_level`` (the lowest priority by default); ``finished()`` yields each outcome in order as
    it ends. A command that fails ends the chain (the ones after it do not start). ``stop()`` ends
    the running command and the chain."""

    def __init__(self, commands: Sequence[tuple[str, Sequence[str]]], nice_level: int = LOWEST_PRIORITY_NICE):
        self.nice_level = nice_level
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
                process = subprocess.Popen(at_priority(argv, self.nice_level), stdin=subprocess.DEVNULL, stdout=log,
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


class BehindTogether:
    """Start ``commands`` ((title, argv, nice_level) triples) at once, each in a chain of its own
    (``BehindChain``) at its own priority, instead of each waiting for the one before.
    ``finished()`` yields the outcomes in the order given."""

    def __init__(self, commands: Sequence[tuple[str, Sequence[str], int]]):
        self._chains = [BehindChain([(title, argv)], nice_level) for title, argv, nice_level in commands]

    @property
    def reaped_cpu_s(self) -> float:
        """CPU seconds of the commands ended so far (see ``BehindChain.reaped_cpu_s``)."""
        return sum(chain.reaped_cpu_s for chain in self._chains)

    def finished(self) -> Iterator[Finished]:
        """Each command's outcome in the order given, waiting for it to end."""
        for chain in self._chains:
            yield from chain.finished()

    def stop(self) -> None:
        """End every command still running."""
        for chain in self._chains:
            chain.stop()
