"""docs/design/fusion.md's generated tables: pooling, targets and fast-against-full from run files."""

from __future__ import annotations

import json

import pytest

from experiments.fusion_runs import CONTROLLERS, run_name
from experiments.results.fusion_pages import fusion_section, pooled
from experiments.results.sources import FUSION


def controller(savings: float, oracle_savings: float, lit: float | None, entries: int) -> dict:
    return {"savings_vs_always_on": savings, "savings_vs_oracle": savings / oracle_savings,
            "lit_on_entry_rate": lit, "zone_entries": entries, "gap_unseen": 0.0,
            "gap_unused": (oracle_savings - savings) / oracle_savings, "dark_unseen": 0.0,
            "dark_unused": None if lit is None else 1.0 - lit, "lag_p95_s": 0.0, "false_on_time_s": 100.0}  # fmt: skip


def run_file(oracle_savings: float, fused_savings: float, fused_lit: float, entries: int, seed: int) -> dict:
    controllers = {name: controller(oracle_savings, oracle_savings, 1.0, entries) for name in CONTROLLERS}
    controllers["always_on"] = controller(0.0, oracle_savings, 1.0, entries)
    controllers["detector_fused"] = controller(fused_savings, oracle_savings, fused_lit, entries)
    return {"scenario": "suburban_night_two_way", "seed": seed, "cpu_s": 600.0, "controllers": controllers}


def test_pooled_share_is_saved_energy_over_saved_energy_and_lit_is_entry_weighted():
    # a busy run (oracle 30 %, fused 27 %, 90 % of 100 entries lit) and a quiet one (oracle 60 %,
    # fused 60 %, all of 10 entries lit): (27 + 60) / (30 + 60) = 0.9667, not the mean of the
    # shares 0.95; lit (90 + 10) / 110 = 0.909, not the mean of the rates 0.95
    runs = [run_file(0.30, 0.27, 0.90, 100, 1), run_file(0.60, 0.60, 1.0, 10, 2)]
    p = pooled(runs, "detector_fused")
    assert p["share"] == pytest.approx(87 / 90)
    assert p["lit"] == pytest.approx(100 / 110)
    assert p["entries"] == 110


def test_section_reports_targets_met_and_missed_and_fast_against_full(tmp_path):
    folder = tmp_path / FUSION.file
    folder.mkdir()
    for hour in (0, 4):
        for seed in (1, 2, 3):
            full = run_file(0.40, 0.38, 0.995, 50, seed)  # 0.95 of the oracle, 99.5 % lit: both met
            fast = run_file(0.40, 0.34, 0.97, 50, seed)  # 10 points below full, 2.5 points darker
            for fidelity, data in (("full", full), ("fast", fast)):
                path = folder / f"{run_name('suburban_night_two_way', hour, seed, fidelity)}.json"
                path.write_text(json.dumps(data))
    text = fusion_section(tmp_path)
    two_way, one_way = text.split("### suburban_night\n")
    assert two_way.count("| 22:00 |") == 2 * 3 and two_way.count("| 02:00 |") == 2 * 3
    assert "(met: 0.950) with >= 99 % lit on entry (met: 99.5 %)" in two_way
    assert "(missed: 0.850) with >= 99 % lit on entry (missed: 97.0 %)" in two_way
    assert "| detector_fused | 38.0 % / 34.0 % (misses by 2.0 points) | 99.5 % / 97.0 % (misses by 1.5 points) |" \
        in two_way
    assert "| pir | 40.0 % / 40.0 % (agrees) |" in two_way
    assert "The whole fast night: not measured." in two_way
    assert one_way.count("Not measured.") == 2
