"""Staging folders of output folders: removed when their job dies, whatever killed it."""

import os
import signal
import subprocess
import sys

import pytest

from detector.outdir import (
    TERMINATED_EXIT,
    exit_on_terminate,
    raise_if_terminated,
    remove_orphan_stages,
    staged_output,
    stop_on_signals,
)


def dead_pid() -> int:
    """The id of a process that has ended (a finished child, reaped)."""
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(child.stdout)


def test_stage_of_a_killed_job_is_removed_by_the_next_one(tmp_path):
    out = tmp_path / "run"
    orphan = tmp_path / f".run.partial-{dead_pid()}-abc123"
    orphan.mkdir()
    (orphan / "summary.json").write_text("{}")
    alive = tmp_path / f".run.partial-{os.getpid()}-def456"  # a job still running beside it
    alive.mkdir()
    unnamed = tmp_path / ".run.partial-xyz"  # no process id in the name: not ours to judge
    unnamed.mkdir()
    other = tmp_path / f".other.partial-{dead_pid()}-abc"  # another output's stage
    other.mkdir()
    with staged_output(out) as stage:
        (stage / "summary.json").write_text("{}")
        assert not orphan.exists()
        assert alive.exists() and unnamed.exists() and other.exists()
    assert (out / "summary.json").exists()
    assert not stage.exists()


def test_removing_orphans_says_which(tmp_path):
    out = tmp_path / "run"
    orphan = tmp_path / f".run.partial-{dead_pid()}-1"
    orphan.mkdir()
    assert remove_orphan_stages(out) == [orphan]
    assert remove_orphan_stages(out) == []


class _SignalsItselfWhenFreed:
    """Sends this process SIGTERM from ``__del__``, a callback whose exceptions Python prints and
    ignores, as it does for one raised in a cffi callback (pymunk freeing a body)."""

    def __del__(self):
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(1000):  # the handler runs between bytecodes, here, inside the callback
            pass


def test_a_sigterm_whose_exception_a_callback_swallowed_still_stops_the_job(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as stopped, exit_on_terminate():
        with staged_output(out) as stage:
            (stage / "summary.json").write_text("{}")
            _SignalsItselfWhenFreed()  # freed at once: the handler's SystemExit is lost in __del__
            (stage / "lamps.csv").write_text("went on")  # ... and the job went on
    assert stopped.value.code == TERMINATED_EXIT
    assert not out.exists() and not list(tmp_path.iterdir())
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL


def test_a_library_broken_by_a_swallowed_stop_ends_as_the_stop_and_quietly(tmp_path, capsys):
    # Ctrl-C while numba compiles: the handler's exception is lost in a ctypes callback, and numba
    # then fails in its own words; the user sees the stop (130), not numba's traceback
    with pytest.raises(SystemExit) as stopped, stop_on_signals():
        _SignalsItselfWhenFreed()
        raise RuntimeError("no compiled object yet")
    assert stopped.value.code == TERMINATED_EXIT
    assert isinstance(stopped.value.__cause__, RuntimeError)
    assert "Interrupted" not in capsys.readouterr().err  # no "Exception ignored ..." report
    with pytest.raises(RuntimeError), stop_on_signals():  # without a stop, an error stays an error
        raise RuntimeError("a real fault")


def test_raise_if_terminated_is_quiet_without_a_signal():
    with exit_on_terminate():
        raise_if_terminated()  # a fresh block forgets an earlier block's signal
