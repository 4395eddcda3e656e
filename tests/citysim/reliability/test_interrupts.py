"""Ctrl-C and SIGTERM on real `citysim run` processes with a pool of workers: one line, exit
130 / 143, no traceback, every worker gone, the earlier run folder as it was, nothing hidden left."""

from __future__ import annotations

import os
import signal

import pytest

from tests.citysim.reliability.processes import group_gone, lines, start, stop, wait_for, workers
from tests.citysim.test_cli import tiny

#: a night far longer than the test: it is stopped while its workers simulate
LONG_NIGHT = ("--duration", "86400", "--fidelity", "fast", "--controllers", "pir", "--workers", "2")


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_a_stopped_run_says_so_in_one_line_and_leaves_the_earlier_folder(tmp_path, signum):
    out = tmp_path / "run"
    out.mkdir()
    (out / "summary.json").write_text('{"earlier": true}')  # an earlier run folder, to be replaced
    proc = start("run", str(tiny(tmp_path)), "--out", str(out), *LONG_NIGHT)
    try:
        wait_for(lambda: len(workers(proc.pid)) == 2 and list(tmp_path.glob(".run.partial-*")), proc,
                 "the pool's two workers started")  # fmt: skip
        os.killpg(proc.pid, signum)  # the whole group, as a terminal's Ctrl-C and `timeout` do
        _, err = proc.communicate(timeout=120)
    finally:
        stop(proc)
    assert proc.returncode == 128 + signum
    assert lines(err) == [f"interrupted: {out} left as it was"], err
    assert group_gone(proc.pid), "a worker outlived the stopped run"
    assert (out / "summary.json").read_text() == '{"earlier": true}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run", "scene_b.yaml", "tiny.yaml"]  # no stage, no lock


@pytest.mark.slow
def test_sigterm_to_the_command_alone_stops_its_workers_too(tmp_path):
    """`kill PID` reaches the command, not its workers: they end because it does, and a new
    folder is not created."""
    out = tmp_path / "new" / "run"
    proc = start("run", str(tiny(tmp_path)), "--out", str(out), *LONG_NIGHT)
    try:
        wait_for(lambda: len(workers(proc.pid)) == 2, proc, "the pool's two workers started")
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=120)
    finally:
        stop(proc)
    assert proc.returncode == 143
    assert lines(err) == ["interrupted: nothing written"], err
    assert group_gone(proc.pid)
    assert not (tmp_path / "new").exists()  # the parent folder the run made is gone with it
