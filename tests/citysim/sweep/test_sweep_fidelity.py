"""Sweeps in fast mode: one sensor model per camera setup, a sample of points re-run in full."""

from __future__ import annotations

import json

import pytest
import yaml

from citysim.sim.calibration import DEFAULT_DURATION_S, DEFAULT_RUNS, model_path
from citysim.sweep.fidelity import check_points, check_report
from citysim.sweep.runner import SweepError, load_sweep, run_sweep
from tests.citysim.fast.synthetic import constant_model, tiny_scenario

SWEEP = {"name": "fast_density", "base": "tiny.yaml", "seeds": [3], "duration_s": 10,
         "controllers": ["always_on", "detector_confirmed"], "axes": {"traffic_density": [0.5, 1, 2]}}  # fmt: skip


def write_sweep(folder, sweep=SWEEP):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "tiny.yaml").write_text(yaml.safe_dump(tiny_scenario()))
    (folder / "sweep.yaml").write_text(yaml.safe_dump(sweep))
    return folder / "sweep.yaml"


def test_check_points_are_spread_over_the_sweep():
    assert check_points(10, 2) == [0, 9]
    assert check_points(10, 3) == [0, 4, 9] or check_points(10, 3) == [0, 5, 9]
    assert check_points(3, 5) == [0, 1, 2]
    assert check_points(10, 0) == [] and check_points(0, 2) == []


def test_check_report_counts_agreeing_figures():
    def summary(savings, lit, lag, false_on):
        return {"controllers": {"c": {"savings_vs_always_on": savings, "lit_on_entry_rate": lit, "lag_p95_s": lag,
                                      "false_on_time_s": false_on}}}  # fmt: skip

    report = check_report([("p", summary(0.40, 0.95, 1.0, 100.0), summary(0.41, 0.93, 1.2, 120.0))])
    cells = report["points"]["p"]["c"]
    assert cells["savings"]["pass"] and cells["lag_p95_s"]["pass"]
    assert not cells["lit_on_entry"]["pass"] and not cells["false_on_s"]["pass"]  # 2 points; 20 %
    assert (report["cells"], report["cells_pass"]) == (4, 2)


@pytest.mark.slow
def test_a_fast_sweep_uses_one_cached_model_and_checks_a_point_in_full(tmp_path):
    sweep_file = write_sweep(tmp_path / "in")
    resolved = load_sweep(sweep_file)
    cache = tmp_path / "cache"
    # the density axis changes no camera: every point shares the one model, found in the cache
    paths = {model_path(resolved.scenario_for(p), cache, DEFAULT_DURATION_S, DEFAULT_RUNS) for p in resolved.points()}
    assert len(paths) == 1
    constant_model(0.8).save(paths.pop())
    out = tmp_path / "out"
    counts = run_sweep(sweep_file, out, workers=1, progress=False, full_checks=1, cache_dir=cache)
    assert (counts["ok"], counts["failed"]) == (3, 0)
    check = json.loads((out / "fidelity_check.json").read_text())
    assert len(check["points"]) == 1 and counts["check"]["points"] == 1
    (checked,) = check["points"].values()
    assert set(checked) == {"always_on", "oracle", "detector_confirmed"}
    # always_on needs no sensor: both fidelities give the same figures
    assert all(cell["pass"] for cell in checked["always_on"].values())
    assert json.loads((out / "sweep.json").read_text())["fidelity"] == "fast"
    with pytest.raises(SweepError, match="fidelity: .* holds fast results"):
        run_sweep(sweep_file, out, workers=1, progress=False, fidelity="full")


def test_an_unknown_fidelity_is_refused_before_any_work(tmp_path):
    sweep_file = write_sweep(tmp_path / "in")
    with pytest.raises(SweepError, match="fidelity: unknown 'quick'; valid: full, fast"):
        run_sweep(sweep_file, tmp_path / "out", progress=False, fidelity="quick")
    assert not (tmp_path / "out").exists()
