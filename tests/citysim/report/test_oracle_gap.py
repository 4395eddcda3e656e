"""The per-lamp gap to the oracle: hand-made summaries, and a real run's per-lamp energies."""

from pathlib import Path

import pytest

from citysim.config.scenario import scenario_from_mapping
from citysim.report.oracle_gap import oracle_gap_wh, plot_oracle_gap
from citysim.sim.compare import run_comparison
from tests.citysim.sim.test_loop import tiny_scenario


def test_the_gap_is_each_lamps_energy_minus_the_oracles_in_wh():
    controllers = {
        "always_on": {"controller": "always_on", "energy_per_lamp_kwh": [0.05, 0.05, 0.05]},
        "oracle": {"controller": "oracle", "energy_per_lamp_kwh": [0.010, 0.020, 0.030]},
        "pir": {"controller": "pir", "energy_per_lamp_kwh": [0.012, 0.019, 0.030]},
        "located ahead": {"controller": "detector_located", "energy_per_lamp_kwh": [0.020, 0.020, 0.031]},
    }
    gaps = oracle_gap_wh(controllers)
    assert list(gaps) == ["pir", "located ahead"]  # always-on and the bound itself are not drawn
    assert gaps["pir"] == pytest.approx([2.0, -1.0, 0.0])
    assert gaps["located ahead"] == pytest.approx([10.0, 0.0, 1.0])


def test_no_gap_without_an_oracle_or_per_lamp_energies(tmp_path):
    assert oracle_gap_wh({"pir": {"controller": "pir", "energy_per_lamp_kwh": [0.1]}}) is None
    older = {"oracle": {"controller": "oracle"}, "pir": {"controller": "pir", "energy_per_lamp_kwh": [0.1]}}
    assert oracle_gap_wh(older) is None
    assert plot_oracle_gap({"controllers": older}, 3, tmp_path / "gap.png") is None
    assert not (tmp_path / "gap.png").exists()


def test_a_runs_lamps_add_up_to_its_energy_and_the_gap_is_drawn(tmp_path):
    scenario = scenario_from_mapping(tiny_scenario())
    summary = run_comparison(scenario, ["pir"], out_dir=tmp_path / "run")
    for figures in summary["controllers"].values():
        per_lamp = figures["energy_per_lamp_kwh"]
        assert len(per_lamp) == summary["lamps"]
        assert sum(per_lamp) == pytest.approx(figures["energy_kwh"], rel=1e-12)
    # always-on draws the same at every lamp; the oracle never more than always-on at any
    on, bound = (summary["controllers"][n]["energy_per_lamp_kwh"] for n in ("always_on", "oracle"))
    assert max(on) == pytest.approx(min(on), rel=1e-12)
    assert all(b <= a for a, b in zip(on, bound, strict=True))
    path = plot_oracle_gap(summary, 1, Path(tmp_path) / "plots" / "oracle_gap.png")
    assert path is not None and path.stat().st_size > 0
