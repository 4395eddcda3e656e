"""The comparison as plain text: the table `citysim run` prints, one line per controller."""

from __future__ import annotations

from citysim.report.oracle_gap import gap_line
from citysim.report.wording import (
    BELOW_FULL,
    best_installable_sentence,
    oracle_saves_nothing,
    over_oracle_note,
)
from citysim.sim.compare import REFERENCE_CONTROLLERS
from citysim.world.approaches import describe_short


def _pct(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f} %"


def _num(value: float | None, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def _interval(c: dict) -> str:
    """A controller's lit-on-entry 95 % interval as "lo-hi" %; "-" for the references, which light
    every entry by definition, and where there is none."""
    interval = c.get("lit_on_entry_interval_95")
    if interval is None or c.get("controller") in REFERENCE_CONTROLLERS:
        return "-"
    return f"{100 * interval[0]:.1f}-{100 * interval[1]:.1f}"


def split_line(summary: dict) -> str | None:
    """The gap to the oracle's savings split in two (``oracle_seen`` in the run): what no camera can
    see, and per camera controller what its cameras saw and it did not use; None without oracle_seen."""
    controllers = summary["controllers"]
    seen = next((c for c in controllers.values() if c.get("controller") == "oracle_seen"), None)
    if seen is None or seen.get("gap_unseen") is None or oracle_saves_nothing(controllers):
        return None
    unused = [f"{name} {100 * c['gap_unused']:+.1f} / {100 * c['dark_unused']:+.1f}" for name, c in controllers.items()
              if c.get("gap_unused") is not None and c.get("dark_unused") is not None
              and c.get("controller") not in (*REFERENCE_CONTROLLERS, "oracle_seen", "schedule")]  # fmt: skip
    return (f"the gap to the oracle split (points of the oracle's savings / of zone entries): no camera can see "
            f"{100 * seen['gap_unseen']:+.1f} / {_pct(seen.get('dark_unseen'))} of entries (oracle_seen: the oracle "
            f"knowing only what a perfect detector in these cameras sees); the cameras saw and the controller did "
            f"not use: " + (", ".join(unused) or "-"))


def comparison_table(summary: dict) -> str:
    """The planner's two axes first (savings against always-on and the oracle's bound; the share
    of zone entries already lit), then darkness, lag and energy spent on nobody."""
    head = (f"{'controller':<20} {'energy kWh':>10} {'savings':>8} {'vs oracle':>9} {'lit entry':>9} "
            f"{'95 % range':>11} {'below-full s/100':>16} {'lag p95 s':>9} {'never full':>10} {'false on lamp-s':>15}")  # fmt: skip
    no_bound = oracle_saves_nothing(summary["controllers"])
    lines = [f"{summary['scenario']}: {summary['duration_s']:.0f} s simulated, seed {summary['seed']}",
             head, "-" * len(head)]  # fmt: skip
    for name, c in summary["controllers"].items():
        lines.append(
            f"{name:<20} {c['energy_kwh']:>10.3f} {_pct(c['savings_vs_always_on']):>8} "
            f"{_pct(None if no_bound else c.get('savings_vs_oracle')):>9} {_pct(c.get('lit_on_entry_rate')):>9} "
            f"{_interval(c):>11} "
            f"{_num(c.get('dark_s_per_100_entries'), '16.1f'):>16} {_num(c['lag_p95_s'], '9.2f'):>9} "
            f"{c['unlit_crossings']:>10d} {c['false_on_time_s']:>15,.0f}"
        )
    lines.append("savings: energy saved against always-on lamps on the same night; vs oracle: that saving as a "
                 "share of the perfect-knowledge bound's; lit entry: share of zone entries whose lamp was "
                 "already at full level; 95 % range: how far that share could be off from this run's road users "
                 f"alone (few road users, wide range); below-full s/100: seconds road users spent in a zone whose "
                 f"lamp was {BELOW_FULL}, per 100 zone entries; never full: zone entries whose lamp never reached "
                 "full level while the road user was in the zone.")
    notes = (no_bound or over_oracle_note(summary["controllers"]), best_installable_sentence(summary["controllers"]))
    for note in notes:
        if note:
            lines.append(note)
    coverage = summary.get("coverage")
    if coverage:
        blind = ", ".join(f"{a:.0f}-{b:.0f}" for a, b in coverage["blind_stretches_m"]) or "none"
        lines.append(f"camera coverage: {100 * coverage['street_seen']:.0f} % of the lanes and sidewalks in the "
                     f"lamp zones is seen whole within 25 m by some camera; blind stretches (x, m): {blind}")
    split = split_line(summary)
    if split:
        lines.append(split)
    gap = gap_line(summary)
    if gap:
        lines.append(gap)
    short = describe_short(summary.get("approaches") or {})
    if short:
        lines.append(short)
    return "\n".join(lines)
