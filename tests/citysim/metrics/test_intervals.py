"""The lit-on-entry rate's 95 % interval: Wilson by hand, road users as the unit, and a real run's."""

import collections
import csv

import pytest

from citysim.config.scenario import scenario_from_mapping
from citysim.metrics.intervals import lit_share_interval, wilson_interval
from citysim.sim.compare import run_comparison
from tests.citysim.sim.test_loop import tiny_scenario


def test_wilsons_interval_against_a_hand_computed_one():
    # 8 of 10: centre (0.8 + 0.192) / 1.384 = 0.7168, half 1.96 * sqrt(0.016 + 0.0096) / 1.384 = 0.2266
    lo, hi = wilson_interval(0.8, 10.0)
    assert lo == pytest.approx(0.4902, abs=2e-4) and hi == pytest.approx(0.9433, abs=2e-4)
    assert wilson_interval(1.0, 50.0)[1] == 1.0 and wilson_interval(0.0, 50.0)[0] == 0.0


def test_entries_of_one_road_user_count_together():
    # the same 40 of 50 entries lit: ten road users dark in all five of their zones, or ten dark entries
    # spread over fifty road users; the first says far less about the next road user
    clustered = lit_share_interval([(1.0, [(5, 5)] * 8 + [(5, 0)] * 2)])
    spread = lit_share_interval([(1.0, [(1, 1)] * 40 + [(1, 0)] * 10)])
    assert clustered[0] < spread[0] < 0.8 < spread[1] < clustered[1]
    assert lit_share_interval([(1.0, [])]) is None


def test_a_runs_interval_is_its_road_users_resampled(tmp_path):
    summary = run_comparison(scenario_from_mapping(tiny_scenario()), ["pir"], out_dir=tmp_path / "run")
    tallies = collections.defaultdict(lambda: collections.defaultdict(lambda: [0, 0]))
    with open(tmp_path / "run" / "objects.csv", newline="") as fh:
        for row in csv.DictReader(fh):
            tally = tallies[row["controller"]][row["object_id"]]
            tally[0] += 1
            tally[1] += int(row["lit_on_entry"])
    for label, figures in summary["controllers"].items():
        objects = [tuple(t) for t in tallies[label].values()]
        assert sum(lit for _, lit in objects) / sum(e for e, _ in objects) == pytest.approx(figures["lit_on_entry_rate"])
        assert figures["lit_on_entry_interval_95"] == pytest.approx(lit_share_interval([(1.0, objects)]))
        lo, hi = figures["lit_on_entry_interval_95"]
        assert lo <= figures["lit_on_entry_rate"] <= hi
