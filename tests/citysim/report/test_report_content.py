"""What the report and the run plots tell a planner: captions, numbers for people, the window,
the few-objects warning, why a controller saves nothing, never-lit crossings apart from the lag
CDF, lamp levels as true levels one panel per controller, clock time, objects in every legend.

Most checks read the real run folder of conftest.py (a tiny scenario through the simulator);
the lag CDF and the formatting are also checked on made-up inputs whose answer is known.
"""

from __future__ import annotations

import csv
import json
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from citysim.report import lag_cdf, oracle_gap, run_plots
from citysim.report.captions import caption_for
from citysim.report.common import (
    FEW_OBJECTS,
    clock_text,
    fmt_num,
    fmt_pct,
    fmt_quantity,
    plt,
    set_clock_axis,
    warn_few_objects,
)
from citysim.report.html import write_report
from citysim.report.lag_cdf import draw_lag_cdf, lag_groups
from citysim.report.run_plots import (
    RUN_PLOTS,
    TRAFFIC_PLOTS,
    draw_lamp_levels,
    level_data,
    plot_run,
)
from citysim.report.runfacts import (
    RunFacts,
    load_summary,
    read_passages,
    run_facts,
    zero_savings_reasons,
)

CLOCK = re.compile(r"^\d\d:\d\d(:\d\d)?$")


class Page(HTMLParser):
    """Figures of report.html: each <img>'s file name and its <figcaption> text; all visible text."""

    def __init__(self) -> None:
        super().__init__()
        self.figures: list[dict] = []
        self.text: list[str] = []
        self.classes: list[str] = []
        self._in_caption = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.classes.append(a.get("class") or "")
        if tag == "figure":
            self.figures.append({"img": None, "caption": ""})
        elif tag == "img" and self.figures:
            self.figures[-1]["img"] = a.get("alt")
        elif tag == "figcaption":
            self._in_caption = True

    def handle_endtag(self, tag):
        if tag == "figcaption":
            self._in_caption = False

    def handle_data(self, data):
        self.text.append(data)
        if self._in_caption:
            self.figures[-1]["caption"] += data


def parse(html: str) -> Page:
    page = Page()
    page.feed(html)
    return page


@pytest.fixture(scope="module")
def report(tmp_path_factory, run_dir) -> tuple[Path, str]:
    folder = Path(shutil.copytree(run_dir, tmp_path_factory.mktemp("report") / "run"))
    return folder, write_report(folder).read_text()


# --- captions ------------------------------------------------------------------------------


def test_every_figure_has_a_sentence_saying_what_it_shows(report):
    folder, html = report
    page = parse(html)
    shown = [f["img"] for f in page.figures]
    assert sorted(shown) == sorted(p.name for p in (folder / "plots").glob("*.png"))
    assert set(shown) == set(RUN_PLOTS)
    for f in page.figures:
        caption = f["caption"].replace(f"(plots/{f['img']})", "").strip()
        # a title and at least one full sentence, not the file name
        assert len(caption) > 120 and caption.count(". ") >= 1, f["img"]
        assert f["img"] not in caption


def test_a_plot_without_a_caption_is_an_error():
    with pytest.raises(KeyError, match="no caption for plot new_plot.png"):
        caption_for("new_plot.png")
    title, text = caption_for("vs_lamps_spacing_m.png", "sweep", {"lamps_spacing_m": "lamp spacing (m)"})
    assert "lamp spacing (m)" in title and "lamp spacing (m)" in text


# --- numbers for people ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("value", "expected"),
    [(5818.3, "5,818"), (0.05466, "0.0547"), (1.0, "1"), (0.0, "0"), (1234567.0, "1,234,567"),
     (0.000123456, "0.000123"), (None, "-"), (float("nan"), "-"), (-3.25, "-3.25")],
)  # fmt: skip
def test_numbers_print_for_people(value, expected):
    assert fmt_num(value) == expected


def test_quantities_and_percentages():
    assert fmt_quantity(5818.3, "lamp-s") == "5,818 lamp-s"
    assert fmt_quantity(None, "s") == "-"
    assert fmt_pct(0.347) == "34.7 %"
    assert fmt_pct(-0.0123) == "-1.2 %"


def test_report_table_prints_people_numbers_never_exponents(run_dir, tmp_path):
    folder = Path(shutil.copytree(run_dir, tmp_path / "run"))
    summary = json.loads((folder / "summary.json").read_text())
    pir = summary["controllers"]["pir"]
    pir.update(false_on_time_s=5818.3, savings_vs_always_on=0.347, energy_kwh=1234.56,
               dark_exposure_s=0.000012)  # fmt: skip
    (folder / "summary.json").write_text(json.dumps(summary))
    html = write_report(folder).read_text()
    text = " ".join(parse(html).text)
    assert "5,818 lamp-s" in text and "34.7 %" in text and "1,235 kWh" in text
    assert "0.000012 s" in text
    assert not re.search(r"\d(\.\d+)?e[+-]?\d", text), "a number in scientific notation"


# --- the window, the few-objects warning, why 0 % ---------------------------------------------


def test_window_line_gives_clock_hours_and_objects(report, run_dir):
    _, html = report
    passages = read_passages(run_dir / "objects.csv")
    ids = {p["object_id"] for p in passages if p["controller"] == "always_on"}
    text = " ".join(" ".join(parse(html).text).split())
    # 20 s from 22:00
    assert "This run covers 22:00:00-22:00:20" in text
    assert f"{len(ids)} objects crossed a lamp zone" in text


def test_few_objects_warning_shows_below_the_threshold(report):
    _, html = report
    page = parse(html)
    assert "warning" in page.classes
    assert "Few objects: only" in " ".join(page.text)
    facts = RunFacts("x", 600.0, 22.0, objects=FEW_OBJECTS - 1)
    assert facts.warning() is not None and str(FEW_OBJECTS - 1) in facts.warning()
    assert RunFacts("x", 600.0, 22.0, objects=FEW_OBJECTS).warning() is None


def test_a_street_end_without_approach_is_a_warning_in_the_report(run_copy):
    summary = json.loads((run_copy / "summary.json").read_text())
    for short_ends, shown in [(["end"], True), ([], False)]:
        summary["approaches"] = {"first_m": 30.0, "last_m": 0.0, "needed_m": 5.1, "short_ends": short_ends}
        (run_copy / "summary.json").write_text(json.dumps(summary))
        text = " ".join(" ".join(parse(write_report(run_copy).read_text()).text).split())
        assert ("the end lamp zones reach the street's end (0 m)" in text) is shown, short_ends


def test_few_objects_warning_on_the_plots(run_copy, monkeypatch):
    drawn = []
    save = run_plots.save

    def keep(fig, path):
        drawn.append((path.name, [t.get_text() for t in fig.texts]))
        return save(fig, path)

    monkeypatch.setattr(run_plots, "save", keep)
    monkeypatch.setattr(lag_cdf, "save", keep)
    monkeypatch.setattr(oracle_gap, "save", keep)
    plot_run(run_copy)
    assert {name for name, _ in drawn} == set(TRAFFIC_PLOTS)
    for name, texts in drawn:
        assert any(t.startswith("Few objects: only") for t in texts), name
    fig = plt.figure()
    assert warn_few_objects(fig, FEW_OBJECTS - 1) and not warn_few_objects(fig, FEW_OBJECTS)
    plt.close(fig)


def test_schedule_saving_nothing_is_explained_by_its_window(report, run_dir):
    _, html = report
    summary = load_summary(run_dir)
    assert summary["controllers"]["schedule"]["savings_vs_always_on"] == pytest.approx(0.0, abs=1e-9)
    text = " ".join(" ".join(parse(html).text).split())
    # the steps come from the scenario file: dim to 60 % from 23:00
    assert "schedule saves 0 % because of this window" in text
    assert "23:00 60 %" in text and "it dims only from 23:00" in text


def test_without_the_scenario_file_the_report_says_what_it_does_not_know(run_dir, tmp_path):
    folder = Path(shutil.copytree(run_dir, tmp_path / "run"))
    summary = json.loads((folder / "summary.json").read_text())
    summary["scenario_file"] = str(tmp_path / "gone.yaml")
    (folder / "summary.json").write_text(json.dumps(summary))
    facts = run_facts(folder, summary, read_passages(folder / "objects.csv"))
    assert facts.start_hour is None and "clock hours unknown" in facts.window_line()
    # no steps to quote, but lamps.csv shows the lamps never dimmed
    reason = zero_savings_reasons(folder, summary, facts)["schedule"]
    assert "stayed at full level" in reason
    assert "clock hours unknown" in write_report(folder).read_text()


def test_detection_figures_are_read_against_the_crossings():
    from citysim.report.runfacts import detection_figures, detection_row, detection_sentence

    figures = {"detection": {"frames": 900, "tp": 100, "fn": 300, "tpr": 0.25, "precision": 0.9,
                             "object_passes": 4, "missed_passes": 1, "miss_rate": 0.25}}  # fmt: skip
    passages = [{"controller": "detector", "cls": "pedestrian", "never_lit": False, "lit_on_entry": True}] * 3
    passages += [{"controller": "detector", "cls": "pedestrian", "never_lit": True, "lit_on_entry": False}]
    found = detection_figures("detector", figures, passages)
    row = detection_row(found)
    assert row == ["detector", "25.0 %", "90.0 %", "100", "1 of 4 (25.0 %)", "3 of 4 (75.0 %)", "3 of 4 (75.0 %)"]
    text = detection_sentence([found], RunFacts("x", 60.0, 22.0))
    assert "25.0 % of the targets in view" in text and "about 100 judged frames" in text
    assert "hold time" in text and "a low per-frame rate still lights lamps in time" in text
    assert detection_figures("pir", {"detection": {}}, passages) is None


# --- lag CDF: never-lit crossings apart -------------------------------------------------------


def made_up_passages() -> list[dict]:
    """pir: 6 entries lit (lags 0 .. 2 s) and 4 never lit during a 100 s stay."""
    lit = [0.0, 0.0, 0.5, 1.0, 1.5, 2.0]
    rows = [{"controller": "pir", "object_id": str(i), "cls": "pedestrian", "lamp": 0, "t_enter_s": 10.0,
             "t_exit_s": 40.0, "lag_s": lag, "lit_on_entry": lag == 0, "never_lit": False}
            for i, lag in enumerate(lit)]  # fmt: skip
    rows += [{"controller": "pir", "object_id": str(10 + i), "cls": "pedestrian", "lamp": 0, "t_enter_s": 0.0,
              "t_exit_s": 100.0, "lag_s": 100.0, "lit_on_entry": False, "never_lit": True}
             for i in range(4)]  # fmt: skip
    return rows


def test_never_lit_is_read_from_objects_csv(tmp_path):
    path = tmp_path / "objects.csv"
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["controller", "object_id", "cls", "lamp", "t_enter_s", "t_exit_s", "lag_s", "dark_s",
                    "lit_on_entry"])  # fmt: skip
        w.writerow(["pir", 1, "pedestrian", 0, "1.000", "9.767", "8.767", "8.767", 0])  # never lit
        w.writerow(["pir", 2, "pedestrian", 0, "1.000", "9.000", "2.500", "2.500", 0])  # lit late
        w.writerow(["pir", 3, "pedestrian", 0, "1.000", "9.000", "0.000", "0.000", 1])  # lit on entry
    assert [p["never_lit"] for p in read_passages(path)] == [True, False, False]


def test_lag_cdf_draws_never_lit_apart_not_as_long_lags():
    groups = lag_groups(made_up_passages(), ["pir"])
    g = groups["pedestrian"]["pir"]
    assert (len(g.lit_lags_s), g.never_lit, g.entries, g.on_entry) == (6, 4, 10, 2)
    fig = draw_lag_cdf(groups, ["pir"], {"pedestrian": 10}, "t")
    curve_ax, bar_ax = fig.axes
    assert curve_ax.get_xlim()[1] < 3.0  # not stretched to the 100 s stays
    (line,) = curve_ax.get_lines()
    assert line.get_xdata().max() < 3.0
    assert line.get_ydata().max() == pytest.approx(0.6)  # the curve tops out at the share lit
    heights = [p.get_height() for p in bar_ax.patches]
    assert heights == [pytest.approx(0.4)]
    assert "never lit" in bar_ax.get_title()
    plt.close(fig)


def test_real_run_never_lit_matches_the_summary(run_dir):
    summary = load_summary(run_dir)
    passages = read_passages(run_dir / "objects.csv")
    for name, f in summary["controllers"].items():
        never = sum(p["never_lit"] for p in passages if p["controller"] == name)
        assert never == f["unlit_crossings"], name
    assert summary["controllers"]["pir"]["unlit_crossings"] >= 1
    groups = lag_groups(passages, list(summary["controllers"]))
    fig = draw_lag_cdf(groups, list(summary["controllers"]), {}, "t")
    never_lit_stays = [p["t_exit_s"] - p["t_enter_s"] for p in passages if p["never_lit"]]
    for ax in fig.axes[::2]:  # the curve panels
        for line in ax.get_lines():
            # a never-lit stay can be plotted only as the end of the axis, never as a step
            steps = set(np.round(line.get_xdata()[1:-1], 3))
            assert not steps & set(np.round(never_lit_stays, 3))
    plt.close(fig)


# --- lamp levels: one panel per controller, true levels, clock time -------------------------------


def test_lamp_levels_are_true_levels_in_one_row_per_controller(run_dir):
    summary = load_summary(run_dir)
    passages = read_passages(run_dir / "objects.csv")
    facts = run_facts(run_dir, summary, passages)
    data = level_data(run_dir, summary, passages, facts)
    fig = draw_lamp_levels(data, facts, "t")
    names = list(summary["controllers"])
    axes = np.array(fig.axes).reshape(len(names), len(data.lamps))
    levels: dict[tuple[str, int], list[float]] = {}
    with open(run_dir / "lamps.csv") as f:
        for r in csv.DictReader(f):
            levels.setdefault((r["controller"], int(r["lamp"])), []).append(float(r["level"]))
    for i, name in enumerate(names):
        assert name in axes[i, 0].get_ylabel()
        for j, lamp in enumerate(data.lamps):
            (line,) = axes[i, j].get_lines()[:1]
            assert np.array_equal(line.get_ydata(), np.array(levels[(name, lamp)])), (name, lamp)
    dim = facts.scenario.lamps.luminaire.dim_level
    pir_row = axes[names.index("pir")]
    assert min(min(ax.get_lines()[0].get_ydata()) for ax in pir_row) == pytest.approx(dim, abs=0)
    assert max(max(ax.get_lines()[0].get_ydata()) for ax in axes[names.index("always_on")]) == 1.0
    labels = [t.get_text() for t in axes[-1, 0].get_xticklabels()]
    assert labels and all(CLOCK.match(t) for t in labels) and labels[0] == "22:00:00"
    legend_texts = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
    assert legend_texts and all(re.search(r"\(n=\d+\)", t) for t in legend_texts)
    plt.close(fig)


def test_clock_axis():
    assert clock_text(22.0, 300.0) == "22:05" and clock_text(23.5, 1800.0, seconds=True) == "00:00:00"
    fig, ax = plt.subplots()
    set_clock_axis(ax, 22.0, 0.0, 300.0)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["22:00", "22:01", "22:02", "22:03", "22:04", "22:05"]
    set_clock_axis(ax, 23.75, 0.0, 7200.0)
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert "00:00" in labels and all(CLOCK.match(t) for t in labels)
    set_clock_axis(ax, None, 0.0, 60.0)
    assert "since the run started" in ax.get_xlabel()
    plt.close(fig)


def test_every_legend_gives_the_number_of_objects(run_copy, monkeypatch):
    legends = []
    save = run_plots.save

    def keep(fig, path):
        for legend in fig.legends + [ax.get_legend() for ax in fig.axes if ax.get_legend()]:
            texts = [legend.get_title().get_text()] + [t.get_text() for t in legend.get_texts()]
            legends.append((path.name, " ".join(texts)))
        return save(fig, path)

    monkeypatch.setattr(run_plots, "save", keep)
    monkeypatch.setattr(lag_cdf, "save", keep)
    monkeypatch.setattr(oracle_gap, "save", keep)
    plot_run(run_copy)
    assert {name for name, _ in legends} == set(TRAFFIC_PLOTS)
    for name, text in legends:
        assert re.search(r"n=\d+", text), (name, text)
