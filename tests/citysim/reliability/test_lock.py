"""One writer per output folder: a second run on the same --out is refused at once naming the
holder; a lock left by a killed process is taken over; the lock file goes at the end."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest

from detector.outlock import OutputLockedError, lock_path, output_lock
from tests.citysim.reliability.processes import lines, run, start, stop, wait_for
from tests.citysim.test_cli import tiny


def dead_pid() -> int:
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(child.stdout)


def test_a_second_holder_is_refused_and_named(tmp_path):
    out = tmp_path / "run"
    with output_lock(out) as stale:
        assert stale is None
        assert lock_path(out).read_text().strip() == str(os.getpid())
        assert lock_path(out).parent == tmp_path and not out.exists()  # beside the folder, not in it
        with pytest.raises(OutputLockedError, match=rf"--out: .*run is being written by process {os.getpid()}"):
            with output_lock(out):  # another open file: flock refuses it as it would another process
                pass
    assert not lock_path(out).exists()


def test_a_lock_left_by_a_dead_process_is_taken_over(tmp_path):
    out = tmp_path / "run"
    gone = dead_pid()
    lock_path(out).write_text(f"{gone}\n")  # the file a SIGKILLed holder leaves: its flock went with it
    with output_lock(out) as stale:
        assert stale == gone
        assert lock_path(out).read_text().strip() == str(os.getpid())
    assert not lock_path(out).exists()


def test_the_lock_removes_the_parent_folders_it_made(tmp_path):
    with output_lock(tmp_path / "a" / "b" / "run"):
        assert (tmp_path / "a" / "b").is_dir()
    assert not (tmp_path / "a").exists()


@pytest.mark.slow
def test_a_second_run_on_the_same_out_is_refused_at_once(tmp_path):
    out = tmp_path / "run"
    scenario = str(tiny(tmp_path))
    first = start("run", scenario, "--out", str(out), "--duration", "86400", "--fidelity", "fast",
                  "--controllers", "pir", "--workers", "1", "--no-progress")  # fmt: skip
    try:
        wait_for(lambda: lock_path(out).exists() and lock_path(out).read_text().strip(), first, "the first run locked")
        second = run("run", scenario, "--out", str(out), "--duration", "20", "--fidelity", "fast")
        assert second.returncode == 2
        assert lines(second.stderr) == [f"error: --out: {out} is being written by process {first.pid} (lock file "
                                        f"{lock_path(out)}); wait for it to finish or choose another folder"]
        os.killpg(first.pid, signal.SIGINT)
        assert first.wait(timeout=120) == 130, first.stderr.read()
    finally:
        stop(first)
    assert not lock_path(out).exists() and not out.exists()


@pytest.mark.slow
def test_a_run_takes_over_the_lock_of_a_killed_run(tmp_path):
    out = tmp_path / "run"
    gone = dead_pid()
    lock_path(out).write_text(f"{gone}\n")
    res = run("run", str(tiny(tmp_path)), "--out", str(out), "--duration", "10", "--fidelity", "fast",
              "--controllers", "pir", "--workers", "1", "--no-progress")  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert f"note: {out}: took over the lock of process {gone}, which is no longer running" in res.stderr
    assert (out / "summary.json").exists() and (out / "report.html").exists()
    assert not lock_path(out).exists()
