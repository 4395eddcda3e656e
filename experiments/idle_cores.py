"""Commands run beside and behind the work in the foreground, their output kept until it is done.

``make demo`` starts the check beside its night (same priority) and the year behind it (nice 19,
only the CPU the night leaves idle). Each command's output is kept and handed over whole once it
has finished, so tables never interleave with the foreground's progress bar.

Design: docs/design/modules.md (Work beside the demo's night)
"""

from __future__ import annotations

import contextlib
import os
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


class BehindCommand:
    """Start one command (``argv``) now, in a thread, at ``nice_level`` (the lowest priority by
    default); ``outcome()`` waits for it to end; ``stop()`` ends it (or keeps it from starting)."""

    def __init__(self, title: str, argv: Sequence[str], nice_level: int = LOWEST_PRIORITY_NICE):
        self.title, self.nice_level = title, nice_level
        self._outcome: Finished | None = None
        self._stopped = threading.Event()
        self._lock = threading.Lock()  # the command starts and stop() looks at it one at a time
        self._running: subprocess.Popen | None = None
        self.reaped_cpu_s = 0.0  # CPU seconds of the command once ended: they count in RUSAGE_CHILDREN
        self._thread = threading.Thread(target=self._run, args=(list(argv),), name=f"behind: {title}", daemon=True)
        self._thread.start()

    def _run(self, argv: list[str]) -> None:
        with tempfile.TemporaryFile() as log:
            t0 = time.perf_counter()
            with self._lock:
                if self._stopped.is_set():
                    return
                process = subprocess.Popen(at_priority(argv, self.nice_level), stdin=subprocess.DEVNULL, stdout=log,
                                           stderr=subprocess.STDOUT)  # fmt: skip
                self._running = process
            # wait4, not wait(): the CPU seconds of this command and of the workers it waited for
            _, status, usage = os.wait4(process.pid, 0)
            process.returncode = exit_code = os.waitstatus_to_exitcode(status)
            self.reaped_cpu_s = cpu_s = usage.ru_utime + usage.ru_stime
            wall_s = time.perf_counter() - t0
            log.seek(0)
            self._outcome = Finished(self.title, exit_code, log.read().decode(errors="replace"), wall_s, cpu_s)

    def outcome(self) -> Finished | None:
        """The command's outcome once it has ended (None: stopped before it started)."""
        self._thread.join()
        return self._outcome

    def stop(self) -> None:
        """End the command if it runs (SIGTERM: its worker pools end with it), or keep it from starting."""
        with self._lock:
            self._stopped.set()
            running = self._running
            if running is not None and running.returncode is None:
                # os.kill, not Popen.terminate: that polls, and a poll could reap the process under wait4
                with contextlib.suppress(ProcessLookupError):  # it ended this very moment
                    os.kill(running.pid, signal.SIGTERM)
        self._thread.join(timeout=10)


class BehindTogether:
    """Start ``commands`` ((title, argv, nice_level) triples) at once, each a ``BehindCommand`` at
    its own priority, instead of each waiting for the one before. ``finished()`` yields the
    outcomes in the order given."""

    def __init__(self, commands: Sequence[tuple[str, Sequence[str], int]]):
        self._commands = [BehindCommand(title, argv, nice_level) for title, argv, nice_level in commands]

    @property
    def reaped_cpu_s(self) -> float:
        """CPU seconds of the commands ended so far (see ``BehindCommand.reaped_cpu_s``)."""
        return sum(command.reaped_cpu_s for command in self._commands)

    def finished(self) -> Iterator[Finished]:
        """Each command's outcome in the order given, waiting for it to end (none for a command
        stopped before it started)."""
        for command in self._commands:
            if (outcome := command.outcome()) is not None:
                yield outcome

    def stop(self) -> None:
        """End every command still running."""
        for command in self._commands:
            command.stop()
