"""Real `python -m citysim` processes for the reliability tests: started in a group of their own
(as a terminal starts a command), signalled as a terminal or a batch system would."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
#: How long a test waits for something that takes a second or two (a loaded machine included), s.
PATIENCE_S = 120.0


def start(*args: str) -> subprocess.Popen:
    """`python -m citysim ARGS` in a new process group, this worktree first on its path."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen([sys.executable, "-m", "citysim", *args], cwd=REPO, env=env, start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip


def run(*args: str) -> subprocess.CompletedProcess:
    """`python -m citysim ARGS` to its end."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-m", "citysim", *args], cwd=REPO, env=env, capture_output=True,
                          text=True, timeout=600)  # fmt: skip


def wait_for(condition, proc: subprocess.Popen, what: str) -> None:
    """Poll ``condition()`` until true; fail naming ``what`` if ``proc`` ended first or never."""
    deadline = time.monotonic() + PATIENCE_S
    while not condition():
        if proc.poll() is not None:
            raise AssertionError(f"the command ended (exit {proc.returncode}) before {what}: {proc.stderr.read()}")
        if time.monotonic() > deadline:
            raise AssertionError(f"never: {what}")
        time.sleep(0.1)


def children(pid: int) -> list[int]:
    """The processes whose parent is ``pid``."""
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout
    return [int(p) for p in out.split()]


def workers(pid: int) -> list[int]:
    """The pool workers (spawned interpreters) of the process ``pid``."""
    out = subprocess.run(["pgrep", "-P", str(pid), "-f", "spawn_main"], capture_output=True, text=True).stdout
    return [int(p) for p in out.split()]


def group_gone(pgid: int) -> bool:
    """Whether every process of the group ``pgid`` has ended, waiting for that up to PATIENCE_S."""
    deadline = time.monotonic() + PATIENCE_S
    while time.monotonic() < deadline:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.1)
    return False


def lines(stderr: str) -> list[str]:
    """The lines a user reads on stderr, the progress bar's redraws left out."""
    return [line for line in stderr.replace("\r", "\n").splitlines() if line.strip() and "%|" not in line]


def stop(proc: subprocess.Popen) -> None:
    """Kill what is left of a test's command and its group."""
    try:
        os.killpg(proc.pid, 9)
    except ProcessLookupError:
        pass
    proc.wait()
