"""The frontier: one point per controller at (lit on entry, savings), the oracle marked."""

import numpy as np

from citysim.report.common import plt
from citysim.report.frontier import frontier_figure, sweep_frontier_figure

CONTROLLERS = {
    "always_on": {"controller": "always_on", "lit_on_entry_rate": 1.0, "savings_vs_always_on": 0.0},
    "oracle": {"controller": "oracle", "lit_on_entry_rate": 1.0, "savings_vs_always_on": 0.45},
    "pir": {"controller": "pir", "lit_on_entry_rate": 0.2, "savings_vs_always_on": 0.55},
    "nothing_yet": {"controller": "detector", "lit_on_entry_rate": None, "savings_vs_always_on": 0.3},
}


def test_each_controller_is_one_point_where_its_figures_say():
    fig = frontier_figure(CONTROLLERS, n_objects=12)
    (ax,) = fig.axes
    points = {c.get_label(): c.get_offsets().data[0].tolist() for c in ax.collections}
    assert points == {"always_on": [1.0, 0.0], "oracle": [1.0, 0.45], "pir": [0.2, 0.55]}
    assert ax.get_legend().get_title().get_text() == "run: n=12 objects"
    assert any(t.get_text().startswith("Few objects") for t in fig.texts)  # 12 objects are few
    assert ax.get_xlim()[1] >= 1.0  # the ideal corner is in view
    plt.close(fig)


def test_a_sweep_draws_one_point_per_setting_and_skips_failed_rows():
    rows = [
        {"controller": "pir", "status": "ok", "lit_on_entry_rate": "0.3", "savings_vs_always_on": "0.5"},
        {"controller": "pir", "status": "ok", "lit_on_entry_rate": "0.4", "savings_vs_always_on": "0.4"},
        {"controller": "pir", "status": "failed", "lit_on_entry_rate": "", "savings_vs_always_on": ""},
    ]
    fig = sweep_frontier_figure(rows)
    (collection,) = fig.axes[0].collections
    assert np.allclose(collection.get_offsets().data, [[0.3, 0.5], [0.4, 0.4]])
    assert collection.get_label() == "pir (n=2)"
    plt.close(fig)
    assert sweep_frontier_figure(rows[2:]) is None


def test_a_bar_through_a_point_spans_its_lit_on_entry_interval():
    from matplotlib.collections import LineCollection

    with_interval = {**CONTROLLERS, "pir": {**CONTROLLERS["pir"], "lit_on_entry_interval_95": [0.12, 0.31]}}
    fig = frontier_figure(with_interval, n_objects=40)
    (ax,) = fig.axes
    bars = [seg for c in ax.collections if isinstance(c, LineCollection) for seg in c.get_segments()]
    assert [np.asarray(seg).tolist() for seg in bars] == [[[0.12, 0.55], [0.31, 0.55]]]  # only pir has one
    assert ax.get_xlim()[0] < 0.12  # the whole bar is in view
    plt.close(fig)


def test_a_one_axis_sweep_joins_each_controllers_settings_in_axis_order_averaged_over_seeds():
    def row(controller, hold_s, seed, lit, saved):
        return {"controller": controller, "status": "ok", "lamps.luminaire.hold_s": hold_s, "seed": seed,
                "lit_on_entry_rate": str(lit), "savings_vs_always_on": str(saved)}  # fmt: skip

    rows = [row("pir", "60", 1, 0.6, 0.30), row("pir", "5", 1, 0.1, 0.70), row("pir", "60", 2, 0.4, 0.40),
            row("pir", "5", 2, 0.2, 0.60), row("pir", "20", 1, 0.3, 0.5)]  # fmt: skip
    fig = sweep_frontier_figure(rows, "lamps.luminaire.hold_s")
    (ax,) = fig.axes
    (line,) = ax.get_lines()
    # 5 < 20 < 60 as numbers (as text "20" < "5" < "60"), each the mean of its seeds
    assert np.allclose(line.get_xydata(), [[0.15, 0.65], [0.3, 0.5], [0.5, 0.35]])
    assert [t.get_text() for t in ax.texts if t.get_text() in {"5", "20", "60"}] == ["5", "20", "60"]
    assert ax.get_legend().get_title().get_text() == "labels: lamps.luminaire.hold_s, mean over seeds"
    plt.close(fig)
