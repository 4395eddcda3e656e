"""Faults outside the user's input: a worker killed mid-run, a full disk. One line, exit 1,
nothing half-written, and the same folder works again."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.citysim.reliability.processes import REPO, lines, run, start, stop, wait_for, workers
from tests.citysim.test_cli import tiny


@pytest.mark.slow
def test_a_worker_killed_mid_run_fails_the_run_naming_its_controller(tmp_path):
    out = tmp_path / "run"
    scenario = str(tiny(tmp_path))
    proc = start("run", scenario, "--out", str(out), "--duration", "86400", "--fidelity", "fast",
                 "--controllers", "pir", "--workers", "2", "--no-progress")  # fmt: skip
    try:
        wait_for(lambda: len(workers(proc.pid)) == 2 and list(tmp_path.glob(".run.partial-*/**/.parts/*.csv")), proc,
                 "the workers simulating (a controller's part file written)")  # fmt: skip
        victim = _busiest(workers(proc.pid))  # a worker mid-task: an idle one has no controller to name
        os.kill(victim, signal.SIGKILL)
        _, err = proc.communicate(timeout=120)
    finally:
        stop(proc)
    assert proc.returncode == 1
    [line] = lines(err)
    assert line.startswith("error: the worker process running ") and "killed by SIGKILL" in line, line
    # the controller's name, or the traffic recorder's, whichever task the worker ran
    assert any(name in line for name in ("controller always_on", "controller oracle", "controller pir",
                                         "the traffic recorder")), line  # fmt: skip
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene_b.yaml", "tiny.yaml"]  # nothing half-written
    again = run("run", scenario, "--out", str(out), "--duration", "10", "--fidelity", "fast",
                "--controllers", "pir", "--workers", "2", "--no-progress")  # fmt: skip
    assert again.returncode == 0, again.stderr
    assert (out / "summary.json").exists() and (out / "report.html").exists()


def _cpu_ticks(pid: int) -> int:
    """User + system clock ticks the process has used so far (/proc/PID/stat fields 14 and 15)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return int(fields[11]) + int(fields[12])


def _busiest(pids: list[int], window_s: float = 1.0) -> int:
    """The process of ``pids`` that used the most CPU over ``window_s``: the one running a task
    (a pool worker waiting for its next task sleeps)."""
    import time

    before = {pid: _cpu_ticks(pid) for pid in pids}
    time.sleep(window_s)
    return max(pids, key=lambda pid: _cpu_ticks(pid) - before[pid])


def _small_disk(tmp_path: Path) -> tuple[Path, list[str], object]:
    """A folder on a 200 KB tmpfs when this process may mount one (root), else a folder and a
    ``preexec_fn`` limiting the command's files to 200 KB (RLIMIT_FSIZE: EFBIG, as a full disk)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if os.geteuid() == 0:
        mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(disk)], capture_output=True)
        if mounted.returncode == 0:
            return disk, ["umount", str(disk)], None

    def limit() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))

    return disk, [], limit


@pytest.mark.slow
def test_a_full_disk_is_one_clear_line_and_nothing_half_written(tmp_path):
    disk, cleanup, limit = _small_disk(tmp_path)
    try:
        out = disk / "run"
        res = subprocess.run([sys.executable, "-m", "citysim", "run", str(tiny(tmp_path)), "--out", str(out),
                              "--duration", "1200", "--fidelity", "fast", "--controllers", "pir", "--workers", "1",
                              "--no-progress"], cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)},
                             capture_output=True, text=True, preexec_fn=limit, timeout=600)  # fmt: skip
        assert res.returncode == 1, res.stderr
        assert lines(res.stderr) == [f"error: no room to write {out} ({os.strerror(_errno(res.stderr))}); nothing "
                                     "written; free some space and run the same command again"], res.stderr
        assert list(disk.iterdir()) == []  # no run folder, no stage, no lock
    finally:
        if cleanup:
            subprocess.run(cleanup, check=True)


def _errno(stderr: str) -> int:
    """ENOSPC (a full tmpfs) or EFBIG (a file-size limit), whichever the message names."""
    import errno

    return errno.ENOSPC if os.strerror(errno.ENOSPC) in stderr else errno.EFBIG
