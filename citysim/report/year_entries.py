"""How many zone entries a year's lit-on-entry rate rests on, and when they are too few to read.

A year's darkness figures come from the response table's short traffic-level runs, a few hundred
entries: the year table prints the count beside each rate and flags a rate that cannot tell 97 %
from 100 % (the rule in ``FEW_ENTRIES_RULE``).
"""

from __future__ import annotations

from collections.abc import Mapping

#: The gap a planner must be able to see: 97 % lit on entry against 100 %, as a share.
TELL_APART = 0.03
#: With no interval (no per-road-user tallies), the entries a share needs: with none of n entries
#: dark, a 95 % upper bound on the dark share is about 3 / n ("rule of three"), below 3 % from 100 on.
RULE_OF_THREE_ENTRIES = round(3 / TELL_APART)
FLAG = "*"
FEW_ENTRIES_RULE = (
    f"{FLAG} too few entries to tell 97 % from 100 %: the rate's 95 % interval is {100 * TELL_APART:.0f} points "
    f"wide or wider (without an interval: fewer than {RULE_OF_THREE_ENTRIES} entries)."
)


def entries_of(result: Mapping, label: str) -> int:
    """The zone entries ``label``'s year rate is read from: its traffic-level runs' entries per hour
    times the measured share of an hour (year.json's ``table`` and ``sample_s``, s)."""
    levels = result["table"]["levels"].values()
    return round(sum(row[label]["zone_entries"] for row in levels if label in row) * result["sample_s"] / 3600.0)


def too_few(label: str, figures: Mapping, entries: int) -> bool:
    """Whether controller ``label``'s year rate (``figures``: its year.json figures) on ``entries``
    zone entries cannot tell 97 % from 100 % (``FEW_ENTRIES_RULE``); False where there is no rate."""
    if figures.get("lit_on_entry_rate") is None:
        return False
    interval = figures.get("lit_on_entry_interval_95")
    if interval is not None:
        return interval[1] - interval[0] >= TELL_APART
    if label in ("always_on", "oracle"):
        return False  # they light every entry by definition: nothing to tell apart
    return entries < RULE_OF_THREE_ENTRIES


def entries_cell(label: str, figures: Mapping, entries: int) -> str:
    """'of 412 entries' beside a rate, flagged with ``FLAG`` when ``too_few``; '' where there is no rate."""
    if figures.get("lit_on_entry_rate") is None:
        return ""
    return f" of {entries:,} entries" + (FLAG if too_few(label, figures, entries) else "")
