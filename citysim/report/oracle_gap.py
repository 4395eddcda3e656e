"""Where each controller spends more than the oracle: its energy above the bound, lamp by lamp.

The oracle lights each zone exactly while someone needs it (``citysim.control.oracle``), so a
controller's energy at one lamp minus the oracle's at the same lamp, on the same night, is what
that lamp cost beyond need: held for a track that went elsewhere, kept at full because no camera
watches the zone's approach, lit by a false alarm. Below zero the lamp was dimmer than the bound
wanted, and someone may have met the dark there. Read from summary.json's ``energy_per_lamp_kwh``
(run folders written before it existed draw no such plot).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from citysim.report.common import controller_color, plt, save, warn_few_objects
from citysim.report.wording import LIT_ENOUGH
from citysim.sim.compare import REFERENCE_CONTROLLERS

#: The sentence a planner reads beside the plot.
HOW_TO_READ = (
    "Each line is a controller; each point is one lamp (in order along the street) and how many "
    "watt-hours that lamp drew beyond what the oracle, which knows where everyone is, needed on "
    "the same night (0 = the bound); under each lamp, the share of its zone some camera sees. A tall "
    "point at one lamp is where a controller's gap to the bound comes from: an end lamp kept at "
    "full because no camera watches the street before it, or a lamp lit for people who went "
    "elsewhere; a point below zero is a lamp dimmer than the oracle's, where someone may have "
    "walked into a zone below full level (dimmed, not necessarily off)."
)



def oracle_gap_wh(controllers: Mapping[str, Mapping]) -> dict[str, list[float]] | None:
    """Per controller of summary.json's ``controllers`` but the references (always-on's gap is every
    lamp's whole dim saving, the oracle's is 0): each lamp's energy minus the oracle's at the same
    lamp, Wh, in lamp order. None without an oracle or per-lamp energies."""
    oracle = next((c for c in controllers.values() if c.get("controller") == "oracle"), None)
    if oracle is None or oracle.get("energy_per_lamp_kwh") is None:
        return None
    bound_kwh = np.asarray(oracle["energy_per_lamp_kwh"], dtype=float)
    gaps = {}
    for label, figures in controllers.items():
        per_lamp = figures.get("energy_per_lamp_kwh")
        if figures.get("controller", label) in REFERENCE_CONTROLLERS or per_lamp is None or len(per_lamp) != len(bound_kwh):
            continue
        gaps[label] = ((np.asarray(per_lamp, dtype=float) - bound_kwh) * 1000.0).tolist()
    return gaps or None


#: ``gap_line`` explains the gap of the controller saving most among those lighting at least
#: ``LIT_ENOUGH`` of zone entries on entry (a gap bought with darkness needs no explaining).


def gap_line(summary: Mapping) -> str | None:
    """One line for the run's table: where the best controller that lights nearly everyone spends
    beyond the oracle (its largest lamp, and how much of that lamp's zone a camera sees); None
    when no controller qualifies or it draws no more than the bound."""
    controllers = summary.get("controllers", {})
    gaps = oracle_gap_wh(controllers)
    if gaps is None:
        return None
    lit = [n for n in gaps if (controllers[n].get("lit_on_entry_rate") or 0.0) >= LIT_ENOUGH]
    if not lit:
        return None
    name = max(lit, key=lambda n: controllers[n].get("savings_vs_always_on") or 0.0)
    total_wh = sum(gaps[name])
    if total_wh <= 0.0:
        return None
    lamp = int(np.argmax(gaps[name]))
    seen = (summary.get("coverage") or {}).get("zone_seen")
    seen_note = f" (a camera sees {100 * seen[lamp]:.0f} % of its zone)" if seen else ""
    return (f"gap to the oracle: {name}, which saves most of the controllers lighting >= {100 * LIT_ENOUGH:.0f} % "
            f"of zone entries on entry, draws {total_wh:.1f} Wh more than the bound; {gaps[name][lamp]:.1f} Wh "
            f"({100 * gaps[name][lamp] / total_wh:.0f} %) of it at lamp {lamp}{seen_note}. plots/oracle_gap.png "
            f"shows every lamp.")


def plot_oracle_gap(summary: Mapping, n_objects: int | None, path: Path) -> Path | None:
    """Write the per-lamp gap plot to ``path``; None (nothing written) when ``oracle_gap_wh`` has none."""
    gaps = oracle_gap_wh(summary.get("controllers", {}))
    if gaps is None:
        return None
    order = list(gaps)
    n_lamps = len(next(iter(gaps.values())))
    fig, ax = plt.subplots(figsize=(max(6.0, 0.55 * n_lamps + 3.0), 4.4))
    lamps = np.arange(n_lamps)
    for label, gap_wh in sorted(gaps.items(), key=lambda item: -sum(item[1])):
        ax.plot(lamps, gap_wh, marker="o", markersize=4, linewidth=1.2, color=controller_color(label, order),
                label=f"{label} ({sum(gap_wh):+.1f} Wh)")  # fmt: skip
    ax.axhline(0.0, color="black", linewidth=1.0)
    ax.annotate("oracle", (n_lamps - 1, 0.0), textcoords="offset points", xytext=(4, 3), fontsize=8)
    seen = (summary.get("coverage") or {}).get("zone_seen")
    if seen is not None and len(seen) == n_lamps:
        ax.set_xticks(lamps, [f"{j}\n{100 * share:.0f} %" for j, share in enumerate(seen)], fontsize=8)
        ax.set_xlabel("lamp (in order along the street) and the share of its zone a camera sees")
    else:
        ax.set_xticks(lamps)
        ax.set_xlabel("lamp (in order along the street)")
    ax.set_ylabel("energy above the oracle's (Wh)")
    ax.set_title(f"{summary.get('scenario', '')}: where each controller spends beyond the bound")
    ax.grid(alpha=0.3)
    runs = "" if n_objects is None else f"run: n={n_objects} objects; "
    ax.legend(title=f"{runs}(in brackets: all lamps)", fontsize=7, title_fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    warn_few_objects(fig, n_objects)
    return save(fig, path)
