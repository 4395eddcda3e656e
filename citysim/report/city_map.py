"""The city's figures from DIR/city.json: the map of streets coloured by payback, and the ranking.

Reads city.json only (``citysim.city.results``). The map draws each street's centreline in the
city's common frame (east, north metres; ``citysim.city.layout``) coloured by its best
controller's payback in years (grey: no controller lights enough entries or pays back), its
lamps as dots, its name beside it. The ranking is a bar per street of that payback, shortest first.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import colors as mcolors  # noqa: E402

from citysim.report.common import save  # noqa: E402

MAP_PLOT = "city_map.png"
RANKING_PLOT = "city_ranking.png"
NO_PAYBACK_COLOUR = "#9a9a9a"


def read_city(folder: Path) -> dict:
    return json.loads((Path(folder) / "city.json").read_text())


def payback_norm(city: dict) -> mcolors.Normalize:
    """Colour scale of the paybacks: 0 to the longest payback or the lifetime, whichever is larger."""
    paybacks = [s["best_payback_years"] for s in city["streets"] if s["best_payback_years"] is not None]
    return mcolors.Normalize(vmin=0.0, vmax=max([city["money"]["lifetime_years"], *paybacks]))


def plot_map(folder: Path, city: dict) -> Path:
    """DIR/plots/city_map.png: streets coloured by payback, lamps as dots, names beside them."""
    fig, ax = plt.subplots(figsize=(8.5, 6.5))
    cmap, norm = plt.get_cmap("viridis_r"), payback_norm(city)
    for street in city["streets"]:
        xs, ys = zip(*street["centreline_m"], strict=True)
        payback = street["best_payback_years"]
        colour = NO_PAYBACK_COLOUR if payback is None else cmap(norm(payback))
        ax.plot(xs, ys, color=colour, lw=5, solid_capstyle="round", zorder=1)
        if street["lamps_m"]:
            lx, ly = zip(*street["lamps_m"], strict=True)
            ax.scatter(lx, ly, s=14, color="#202020", zorder=2)
        mid = (sum(xs) / len(xs), sum(ys) / len(ys))  # the label near the street's middle
        label = street["name"] + ("" if payback is None else f"\n{payback:.1f} y")
        ax.annotate(label, mid, textcoords="offset points", xytext=(0, 9), ha="center", fontsize=7)
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax,
                 label="payback of the best controller (years)")  # fmt: skip
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    where = "streets at their surveyed places" if city["layout"] == "origin" else "streets laid out in a grid"
    ax.set_title(f"{city['city']}: payback per street ({where}; grey: none)")
    ax.grid(alpha=0.25)
    return save(fig, Path(folder) / "plots" / MAP_PLOT)


def plot_ranking(folder: Path, city: dict) -> Path:
    """DIR/plots/city_ranking.png: the best controller's payback per street, ranked, the lifetime marked."""
    ranking = city["ranking"]
    fig, ax = plt.subplots(figsize=(8, 0.9 + 0.35 * len(ranking)))
    cmap, norm = plt.get_cmap("viridis_r"), payback_norm(city)
    names = [f"{r['street']} ({r['controller'] or 'none'})" for r in ranking]
    values = [r["payback_years"] if r["payback_years"] is not None else 0.0 for r in ranking]
    cols = [NO_PAYBACK_COLOUR if r["payback_years"] is None else cmap(norm(r["payback_years"])) for r in ranking]
    ax.barh(range(len(ranking)), values, color=cols)
    ax.set_yticks(range(len(ranking)), names, fontsize=8)
    ax.invert_yaxis()
    ax.axvline(city["money"]["lifetime_years"], color="#b00000", ls="--", lw=1, label="hardware lifetime")
    ax.set_xlabel("payback of the best controller (years)")
    ax.set_title(f"{city['city']}: streets ranked by payback")
    ax.legend(fontsize=8)
    ax.grid(axis="x", alpha=0.3)
    return save(fig, Path(folder) / "plots" / RANKING_PLOT)
