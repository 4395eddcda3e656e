"""Ctrl-C on a real sweep on a local Dask cluster: the points finished are kept, one line says how
many and how to resume, exit 130, no worker traceback."""

from __future__ import annotations

import os
import signal

import pytest
import yaml

from tests.citysim.reliability.processes import group_gone, lines, start, stop, wait_for
from tests.citysim.test_cli import tiny


@pytest.mark.slow
def test_a_stopped_sweep_keeps_its_points_and_says_how_to_resume(tmp_path):
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"name": "stop_me", "base": str(tiny(tmp_path)), "duration_s": 200,
                                     "seeds": [1, 2, 3, 4, 5, 6], "controllers": ["always_on", "pir"],
                                     "axes": {"traffic_density": [0.5, 1, 2, 4]}}))  # fmt: skip
    out = tmp_path / "out"
    proc = start("sweep", str(sweep), "--out", str(out), "--workers", "2", "--fidelity", "full")
    try:
        results = out / "results.csv"
        wait_for(lambda: results.exists() and len(results.read_text().splitlines()) > 1, proc, "a point finished")
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        stop(proc)
    assert proc.returncode == 130
    said = lines(err)  # no worker traceback, no resource-tracker warning of leaked semaphores
    assert len(said) == 1, err
    kept = int(said[0].split("interrupted: ")[1].split(" of ")[0])
    assert said[0] == f"interrupted: {kept} of 24 points kept in {out}; run the same command again to resume"
    assert 1 <= kept < 24
    assert group_gone(proc.pid)
    assert not (tmp_path / ".out.lock").exists()
