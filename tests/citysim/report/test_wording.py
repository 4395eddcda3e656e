"""Report wording a planner could misread: what 'dark' means, savings beyond the oracle, the best
controller, and how many entries a year's lit-on-entry rate rests on."""

from __future__ import annotations

import re

import pytest

from citysim.report.table import comparison_table
from citysim.report.wording import (
    LIT_ENOUGH,
    best_installable,
    best_installable_sentence,
    over_oracle_note,
)
from citysim.report.year_entries import FEW_ENTRIES_RULE, RULE_OF_THREE_ENTRIES, entries_of, too_few
from citysim.report.year_section import year_table


def figures(kind: str, savings: float, lit: float, vs_oracle: float | None = None) -> dict:
    return {"controller": kind, "energy_kwh": 1.0 - savings, "savings_vs_always_on": savings,
            "savings_vs_oracle": vs_oracle, "lit_on_entry_rate": lit, "dark_s_per_100_entries": 0.0,
            "lag_p95_s": 0.0, "unlit_crossings": 0, "false_on_time_s": 0.0}  # fmt: skip


def run_summary(**controllers: dict) -> dict:
    return {"scenario": "s", "duration_s": 600.0, "seed": 1, "controllers": controllers}


def test_the_table_says_dark_means_below_full_not_off():
    text = comparison_table(run_summary(always_on=figures("always_on", 0.0, 1.0)))
    head = text.splitlines()[1]
    assert "below-full s/100" in head and "never full" in head
    assert "dark" not in head and "unlit" not in head
    assert "a schedule's 50 % counts, though it is not off" in text


def test_savings_beyond_the_oracle_are_explained_only_where_they_appear():
    plain = run_summary(oracle=figures("oracle", 0.4, 1.0, 1.0), pir=figures("pir", 0.3, 0.99, 0.75))
    assert over_oracle_note(plain["controllers"]) is None
    assert "vs oracle above 100 %" not in comparison_table(plain)
    beyond = run_summary(oracle=figures("oracle", 0.4, 1.0, 1.0), pir=figures("pir", 0.5, 0.62, 1.25))
    text = comparison_table(beyond)
    assert "vs oracle above 100 %: pir (125 %, lit on entry 62.0 %)" in text
    assert "below full level" in over_oracle_note(beyond["controllers"])


def test_no_share_of_the_oracle_when_the_oracle_saves_nothing():
    # a short run: the oracle's sensing outweighs its dimming, and a share of a negative bound reads as nonsense
    text = comparison_table(run_summary(oracle=figures("oracle", -0.061, 1.0, 1.0),
                                        pir=figures("pir", 0.171, 0.458, -2.799)))  # fmt: skip
    rows = {line.split()[0]: line for line in text.splitlines()[3:5]}
    assert "-279.9 %" not in rows["pir"] and "17.1 %" in rows["pir"]
    assert "vs oracle not given: the oracle saves -6.1 % against always-on" in text
    assert "vs oracle above 100 %" not in text
    # a bound of a few tenths of a percent is no bound either: its summary.json share is None
    small = comparison_table(run_summary(oracle=figures("oracle", 0.004, 1.0, None),
                                         pir=figures("pir", 0.171, 0.458, None)))  # fmt: skip
    assert "the oracle saves 0.4 % against always-on on this run, less than 1 %" in small
    assert "its lamps were at full nearly the whole run" in small


def test_the_best_controller_is_installable_and_lights_the_stated_share():
    controllers = {
        "always_on": figures("always_on", 0.0, 1.0),
        "oracle": figures("oracle", 0.6, 1.0),  # saves most, but nobody can install it
        "pir": figures("pir", 0.55, LIT_ENOUGH - 0.01),  # saves more, but lights too few on entry
        "detector": figures("detector", 0.40, LIT_ENOUGH + 0.02),
        "detector_located": figures("detector_located", 0.45, LIT_ENOUGH),
    }
    assert best_installable(controllers) == "detector_located"
    sentence = best_installable_sentence(controllers)
    assert sentence.startswith("Best controller: detector_located, saving 45.0 %")
    assert f"at least {100 * LIT_ENOUGH:.0f} % of zone entries" in sentence
    assert best_installable(controllers, lit_share=0.99) is None
    assert best_installable_sentence(controllers, lit_share=0.99).startswith("None of the installable controllers")
    assert sentence in comparison_table(run_summary(**controllers))


def year_result(entries_per_hour: float, interval: list[float] | None) -> dict:
    def year_figures(lit: float | None, iv: list[float] | None) -> dict:
        return {"energy_kwh_per_year": 100.0, "savings_vs_always_on": 0.3, "cost_per_year": 30.0,
                "co2_kg_per_year": 40.0, "aeci_wh_per_m2": 500.0, "lit_on_entry_rate": lit,
                "lit_on_entry_interval_95": iv, "dark_s_per_year": 10.0}  # fmt: skip

    level = {label: {"zone_entries": entries_per_hour} for label in ("always_on", "pir", "schedule")}
    return {"currency": "EUR", "sample_s": 360.0,  # a tenth of an hour measured per level
            "table": {"labels": ["always_on", "pir", "schedule"], "levels": {"0.5": level, "1.0": level}},
            "controllers": {"always_on": year_figures(1.0, None), "pir": year_figures(0.985, interval),
                            "schedule": year_figures(None, None)}}  # fmt: skip


def test_the_year_table_prints_the_entries_beside_each_rate():
    result = year_result(2000.0, [0.978, 0.990])
    assert entries_of(result, "pir") == 400  # 2 levels x 2000 per hour x 0.1 h
    rows = {line.split()[0]: line for line in year_table(result).splitlines()[2:5]}
    assert "98.5 % (97.8-99.0) of 400 entries" in rows["pir"]
    assert "of 400 entries" in rows["always_on"] and "entries" not in rows["schedule"]  # no rate, no count
    assert FEW_ENTRIES_RULE not in year_table(result)  # a 1.2-point interval tells 97 % from 100 %


@pytest.mark.parametrize(("interval", "entries_per_hour", "few"), [
    ([0.960, 0.995], 2000.0, True),  # 3.5 points wide: 97 % and 100 % both plausible
    ([0.975, 0.995], 2000.0, False),  # 2 points wide
    (None, RULE_OF_THREE_ENTRIES * 5.0 - 5.0, True),  # no interval: below the rule of three's count
    (None, RULE_OF_THREE_ENTRIES * 5.0, False),
])
def test_a_rate_on_too_few_entries_is_flagged_with_the_rule(interval, entries_per_hour, few):
    result = year_result(entries_per_hour, interval)
    assert too_few("pir", result["controllers"]["pir"], entries_of(result, "pir")) is few
    text = year_table(result)
    assert (FEW_ENTRIES_RULE in text) is few
    pir_row = next(line for line in text.splitlines() if line.startswith("pir"))
    assert pir_row.rstrip().split("entries")[1].startswith("*") is few
    # the references light every entry by definition: never flagged for their count
    assert not too_few("always_on", result["controllers"]["always_on"], 1)


def test_every_caption_that_speaks_of_darkness_says_below_full():
    from citysim.report.captions import CAPTIONS
    from citysim.report.frontier import HOW_TO_READ
    from citysim.report.html import RUN_COLUMNS_HOWTO
    from citysim.report.oracle_gap import HOW_TO_READ as GAP_HOW_TO_READ
    from citysim.report.year_section import MONTHLY_HOWTO, TABLE_HOWTO

    texts = [text for _, text in CAPTIONS.values()]
    texts += [HOW_TO_READ, GAP_HOW_TO_READ, RUN_COLUMNS_HOWTO, MONTHLY_HOWTO, TABLE_HOWTO]
    vague = [t[:60] for t in texts if re.search(r"\bin(to)? the dark\b|\bdim zone|\bunlit\b", t)]
    assert vague == []
    assert all("below full" in t for t in (HOW_TO_READ, RUN_COLUMNS_HOWTO, TABLE_HOWTO))
