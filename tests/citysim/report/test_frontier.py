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


#: Eleven controllers as a night's comparison has them: most crowd the top-right corner.
ELEVEN = {
    "always_on": (1.0, 0.0), "oracle": (1.0, 0.42), "schedule": (0.55, 0.25), "pir": (0.93, 0.38),
    "threshold_5": (0.97, 0.36), "threshold_05": (0.975, 0.35), "detector": (0.96, 0.37),
    "detector_confirmed": (0.965, 0.365), "detector_network": (0.985, 0.39), "detector_located": (0.98, 0.40),
    "fusion": (0.99, 0.41),
}


def _eleven() -> dict:
    return {name: {"controller": name, "lit_on_entry_rate": x, "savings_vs_always_on": y,
                   "lit_on_entry_interval_95": [x - 0.02, min(1.0, x + 0.01)]}
            for name, (x, y) in ELEVEN.items()}  # fmt: skip


def _label_boxes(fig) -> dict:
    from matplotlib.text import Text

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    (ax,) = fig.axes
    return {t.get_text(): Text.get_window_extent(t, renderer) for t in ax.texts if t.get_text() in ELEVEN}


def test_eleven_controllers_labels_do_not_overprint_each_other_or_the_legend():
    fig = frontier_figure(_eleven(), n_objects=300)
    boxes = _label_boxes(fig)
    assert set(boxes) == set(ELEVEN)  # every controller is named once
    names = sorted(boxes)
    overlaps = [(a, b) for i, a in enumerate(names) for b in names[i + 1:] if boxes[a].overlaps(boxes[b])]
    assert overlaps == []
    legend = fig.axes[0].get_legend().get_window_extent(fig.canvas.get_renderer())
    assert [n for n, box in boxes.items() if box.overlaps(legend)] == []
    frame = fig.axes[0].get_window_extent(fig.canvas.get_renderer())
    assert all(frame.x0 <= b.x0 and b.x1 <= frame.x1 and frame.y0 <= b.y0 and b.y1 <= frame.y1 for b in boxes.values())
    plt.close(fig)


def test_the_fixed_offset_labels_would_overprint_on_the_same_summary():
    # the check above can fail: the same eleven names at one fixed offset from their points collide
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    ax.set_xlim(0.5, 1.02)
    ax.set_ylim(-0.02, 0.5)
    for name, (x, y) in ELEVEN.items():
        ax.annotate(name, (x, y), textcoords="offset points", xytext=(5, 4), fontsize=7)
    boxes = _label_boxes(fig)
    names = sorted(boxes)
    assert any(boxes[a].overlaps(boxes[b]) for i, a in enumerate(names) for b in names[i + 1:])
    plt.close(fig)


def test_always_on_and_the_oracle_get_no_interval_bar():
    from matplotlib.collections import LineCollection

    fig = frontier_figure(_eleven(), n_objects=300)
    (ax,) = fig.axes
    bars = [np.asarray(seg) for c in ax.collections if isinstance(c, LineCollection) for seg in c.get_segments()]
    ys = sorted(round(float(seg[0][1]), 3) for seg in bars)
    assert len(bars) == len(ELEVEN) - 2
    assert 0.0 not in ys and 0.42 not in ys  # always_on's and the oracle's savings rows carry none
    plt.close(fig)
