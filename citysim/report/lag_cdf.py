"""The lag CDF of a run or sweep: share of zone entries lit within a given lag, per class, with
the crossings never lit shown apart.

A never-lit crossing has no lag: objects.csv writes its whole stay in the zone as lag_s
(``runfacts.is_never_lit`` recognises it). Drawn as a lag it would stretch the curve to the
longest stays and read as "lit late"; here each curve stops at the share of entries lit and a
bar per controller beside it gives the share never lit.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from citysim.report.common import (
    TARGET_CLASSES,
    controller_color,
    ecdf,
    fmt_pct,
    plt,
    plural,
    save,
    warn_few_objects,
)

__all__ = ["LagGroup", "draw_lag_cdf", "lag_groups", "object_counts", "plot_lag_cdf"]


@dataclass
class LagGroup:
    """One controller's zone entries of one class: lags of those lit, and how many were never lit."""

    lit_lags_s: list[float] = field(default_factory=list)
    never_lit: int = 0
    on_entry: int = 0

    @property
    def entries(self) -> int:
        return len(self.lit_lags_s) + self.never_lit


def lag_groups(passages: list[dict], controllers: list[str]) -> dict[str, dict[str, LagGroup]]:
    """class -> controller -> LagGroup, over target passages (classes in TARGET_CLASSES order).

    A never-lit crossing's lag_s is its whole stay in the zone, not a time to light: it goes
    to ``never_lit``, not into the lags.
    """
    groups: dict[str, dict[str, LagGroup]] = defaultdict(dict)
    for p in passages:
        if p["cls"] not in TARGET_CLASSES or p["controller"] not in controllers:
            continue
        if math.isnan(p["lag_s"]) and not p.get("never_lit"):
            continue
        g = groups[p["cls"]].setdefault(p["controller"], LagGroup())
        if p.get("never_lit"):
            g.never_lit += 1
        else:
            g.lit_lags_s.append(p["lag_s"])
            g.on_entry += bool(p.get("lit_on_entry"))
    return {c: groups[c] for c in TARGET_CLASSES if c in groups}


def object_counts(passages: list[dict]) -> dict[str, int]:
    """class -> distinct target objects (keyed by ``source`` too: a sweep pools many runs)."""
    seen: dict[str, set] = defaultdict(set)
    for p in passages:
        if p["cls"] in TARGET_CLASSES:
            seen[p["cls"]].add((p.get("source", ""), p["object_id"]))
    return {c: len(v) for c, v in seen.items()}


def plot_lag_cdf(passages: list[dict], controllers: list[str], path: Path, title_prefix: str,
                 notes: list[str]) -> Path | None:  # fmt: skip
    """One panel per target class: share of zone entries lit within x seconds, never-lit apart."""
    groups = lag_groups(passages, controllers)
    if not groups:
        notes.append(
            "lag_cdf.png skipped: no target object crossed a lamp zone (objects.csv empty or missing)"
        )
        return None
    objects = object_counts(passages)
    fig = draw_lag_cdf(groups, controllers, objects, f"{title_prefix}illumination lag per class")
    warn_few_objects(fig, sum(objects.values()))
    return save(fig, path)


def draw_lag_cdf(groups: dict[str, dict[str, LagGroup]], controllers: list[str],
                 objects: dict[str, int], title: str) -> Figure:  # fmt: skip
    """One row per class: the CDF of lags of lit entries (it tops out at the share lit), a bar per
    controller beside it with the share never lit, and the legend to the right.

    Rows, not columns: with every controller and three classes a row of panels is too wide to
    read once the page scales it down."""
    classes = list(groups)
    fig = plt.figure(figsize=(11.0, 3.1 * len(classes) + 0.9), layout="constrained")
    grid = fig.add_gridspec(len(classes), 2, width_ratios=[4.0, 1.4])
    first = None
    for k, cls in enumerate(classes):
        ax = fig.add_subplot(grid[k, 0], sharey=first)
        bars = fig.add_subplot(grid[k, 1], sharey=ax)
        first = first or ax
        mine = {n: groups[cls][n] for n in controllers if n in groups[cls]}
        _draw_lit_curves(ax, mine, controllers)
        n_entries = max(g.entries for g in mine.values())
        n_obj = objects.get(cls, 0)
        ax.set_title(f"{cls} (n={n_obj} {plural(n_obj, 'object')}, {n_entries} zone entries)",
                     fontsize=9)  # fmt: skip
        ax.set_ylabel("share of entries lit\nwithin lag", fontsize=8)
        _draw_never_lit(bars, mine, controllers)
        # right of the bars: a CDF's corners are all taken by one curve or another
        handles, labels = ax.get_legend_handles_labels()
        bars.legend(handles, labels, title=f"controller ({cls}: n={n_obj})", fontsize=7,
                    title_fontsize=7, loc="upper left", bbox_to_anchor=(1.04, 1.0))  # fmt: skip
    first.set_ylim(0, 1.05)
    fig.suptitle(f"{title} (0 = lit on entry)\ncurves: entries lit, by lag; bars: entries whose "
                 "lamp never reached full while the object was in the zone", fontsize=10)  # fmt: skip
    return fig


def _draw_lit_curves(ax, groups: dict[str, LagGroup], controllers: list[str]) -> None:
    lag_max = max((max(g.lit_lags_s) for g in groups.values() if g.lit_lags_s), default=0.0)
    right = max(1.0, lag_max * 1.05)
    for n, g in groups.items():
        color = controller_color(n, controllers)
        label = f"{n}: {fmt_pct(g.on_entry / g.entries, 0)} lit on entry"
        if g.lit_lags_s:
            x, y = ecdf(np.array(g.lit_lags_s))
            y = y * len(g.lit_lags_s) / g.entries  # the curve ends at the share lit
            ax.step(np.r_[0.0, x, right], np.r_[0.0, y, y[-1]], where="post", lw=1.5,
                    color=color, label=label)  # fmt: skip
        else:
            ax.plot([0.0, right], [0.0, 0.0], lw=1.5, color=color, label=label)
    ax.set_xlim(0, right)
    ax.set_xlabel("illumination lag (s)", fontsize=8)
    ax.grid(alpha=0.3)


def _draw_never_lit(ax, groups: dict[str, LagGroup], controllers: list[str]) -> None:
    names = list(groups)
    shares = [groups[n].never_lit / groups[n].entries for n in names]
    ax.bar(range(len(names)), shares, color=[controller_color(n, controllers) for n in names],
           edgecolor="black", linewidth=0.5)  # fmt: skip
    for i, n in enumerate(names):
        ax.text(i, shares[i] + 0.02, f"{groups[n].never_lit}", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(range(len(names)), names, rotation=90, fontsize=7)
    ax.tick_params(axis="y", labelleft=False)
    ax.set_title("never lit\n(count on bar)", fontsize=8)
    ax.grid(axis="y", alpha=0.3)
