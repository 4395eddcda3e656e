"""The planner's headline: savings against the share of people who meet a lit street.

Each controller is one point: x is its ``lit_on_entry_rate`` (the share of zone entries whose
lamp was already at full level), y its savings against always-on lamps on the same night. The
ideal corner is top right (all savings, nobody in the dark); the oracle marks the most any
controller can save with everyone lit. For a sweep, each controller draws one point per setting.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from citysim.report.common import controller_color, plt, warn_few_objects
from citysim.report.labels import Label, place_labels
from citysim.sim.compare import REFERENCE_CONTROLLERS

#: The sentence a planner reads beside the plot.
HOW_TO_READ = (
    "Each point is a controller: further right, fewer people walk or drive into a zone whose lamp is "
    "below full level (dimmed counts, though not off); "
    "higher, more energy saved against always-on lamps. The best controllers sit near the "
    "oracle (perfect knowledge of where everyone is, a star), top right; oracle_seen (a cross) is the "
    "oracle knowing only what a perfect detector in the scenario's cameras sees: the height from it "
    "down to a controller is what that controller's cameras saw and it did not use, the height from "
    "the oracle down to it what no camera can see; a point low or to the left "
    "buys its savings with darkness or its light with energy. The bar through a point spans the "
    "95 % interval of its lit-on-entry rate: how far that rate could be off from this run's road "
    "users alone (few road users, wide bars). always_on and the oracle have no bar: both light every "
    "entry by definition."
)


def _axes(title: str):
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    ax.set_xlabel("lit on entry (share of zone entries already at full level)")
    ax.set_ylabel("savings against always-on")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.xaxis.set_major_formatter(plt.FuncFormatter(lambda v, _: f"{100 * v:.0f} %"))
    ax.yaxis.set_major_formatter(plt.FuncFormatter(lambda v, _: f"{100 * v:.0f} %"))
    return fig, ax


def _finish(fig, ax, points: Sequence[tuple[float, float]], legend_title: str):
    xs = [x for x, _ in points] + [1.0]
    ys = [y for _, y in points] + [0.0]
    ax.set_xlim(min(xs) - 0.05, 1.02)
    ax.set_ylim(min(0.0, min(ys)) - 0.02, max(ys) + 0.08)
    ax.annotate("ideal", (1.0, max(ys) + 0.06), ha="right", va="top", fontsize=8, color="#555")
    ax.legend(fontsize=7, loc="lower left", title=legend_title or None, title_fontsize=7)
    return fig


def frontier_figure(controllers: Mapping[str, Mapping], title: str = "savings vs darkness",
                    n_objects: int | None = None):  # fmt: skip
    """One point per controller of a run (summary.json's ``controllers``); None without figures.
    ``n_objects`` (the run's objects) goes in the legend, with a warning when they are few."""
    points = {name: (c.get("lit_on_entry_rate"), c.get("savings_vs_always_on")) for name, c in controllers.items()}
    points = {n: p for n, p in points.items() if p[0] is not None and p[1] is not None}
    if not points:
        return None
    fig, ax = _axes(title)
    order = list(points)
    labels = []
    for name, (x, y) in points.items():
        kind = controllers[name].get("controller")
        oracle = kind in ("oracle", "oracle_seen")  # the bound, and the bound for these cameras
        color = "black" if oracle else controller_color(name, order)
        interval = controllers[name].get("lit_on_entry_interval_95")
        if interval is not None and controllers[name].get("controller") not in REFERENCE_CONTROLLERS:
            ax.errorbar([x], [y], xerr=[[x - interval[0]], [interval[1] - x]], fmt="none", ecolor=color,
                        elinewidth=1.0, capsize=3, alpha=0.6, zorder=2)  # fmt: skip
        marker = {"oracle": "*", "oracle_seen": "P"}.get(kind, "o")
        ax.scatter([x], [y], s=90 if oracle else 45, marker=marker, color=color, label=name, zorder=3)
        labels.append(Label(name, x, y, color))
    warn_few_objects(fig, n_objects)
    lows = [(c["lit_on_entry_interval_95"][0], points[n][1]) for n, c in controllers.items()
            if n in points and c.get("lit_on_entry_interval_95") is not None
            and c.get("controller") not in REFERENCE_CONTROLLERS]  # the bars' left ends in view
    fig = _finish(fig, ax, list(points.values()) + lows, "" if n_objects is None else f"run: n={n_objects} objects")
    place_labels(ax, labels)  # once the limits are final: the boxes are measured in pixels
    return fig


def sweep_frontier_figure(rows: Sequence[Mapping[str, str]], axis: str | None = None):
    """One point per controller and sweep setting (results.csv rows with status ok). With ``axis``
    (the sweep's one varied axis), each controller's settings are averaged over the seeds and
    joined in the axis' order, each point labelled with its value: the curve a knob traces."""
    by_controller: dict[str, list[tuple[float, float, str]]] = {}
    for row in rows:
        try:
            x, y = float(row["lit_on_entry_rate"]), float(row["savings_vs_always_on"])
        except (KeyError, TypeError, ValueError):
            continue
        if row.get("status", "ok") == "ok":
            by_controller.setdefault(row["controller"], []).append((x, y, row.get(axis, "") if axis else ""))
    if not by_controller:
        return None
    title = "savings vs darkness, one point per sweep setting" + (f" ({axis})" if axis else "")
    fig, ax = _axes(title)
    order = list(by_controller)
    drawn: list[tuple[float, float]] = []
    for name, pts in by_controller.items():
        oracle = name in ("oracle", "oracle_seen")
        color = "black" if oracle else controller_color(name, order)
        marker = {"oracle": "*", "oracle_seen": "P"}.get(name, "o")
        style = {"s": 60 if oracle else 25, "marker": marker, "color": color, "zorder": 3}
        if axis is None:
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], alpha=0.8, label=f"{name} (n={len(pts)})", **style)
            drawn += [(x, y) for x, y, _ in pts]
            continue
        curve = _setting_means(pts)
        ax.plot([x for _, x, _ in curve], [y for _, _, y in curve], color=color, alpha=0.6, linewidth=1, zorder=2)
        ax.scatter([x for _, x, _ in curve], [y for _, _, y in curve], label=name, **style)
        if len({(round(x, 4), round(y, 4)) for _, x, y in curve}) > 1:  # always_on's settings all sit at one spot
            for value, x, y in curve:
                ax.annotate(value, (x, y), textcoords="offset points", xytext=(4, 3), fontsize=6, color=color)
        drawn += [(x, y) for _, x, y in curve]
    return _finish(fig, ax, drawn, f"labels: {axis}, mean over seeds" if axis else "n = sweep settings")


def _setting_means(points: Sequence[tuple[float, float, str]]) -> list[tuple[str, float, float]]:
    """(setting, mean lit on entry, mean savings) per setting of ``points`` (x, y, setting), in
    the settings' order (numeric where they are numbers)."""
    by_setting: dict[str, list[tuple[float, float]]] = {}
    for x, y, setting in points:
        by_setting.setdefault(setting, []).append((x, y))

    def key(setting: str) -> tuple[int, float, str]:
        try:
            return (0, float(setting), "")
        except ValueError:
            return (1, 0.0, setting)

    return [(setting, sum(x for x, _ in xy) / len(xy), sum(y for _, y in xy) / len(xy))
            for setting, xy in sorted(by_setting.items(), key=lambda item: key(item[0]))]  # fmt: skip
