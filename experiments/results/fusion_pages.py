"""The generated section of docs/design/fusion.md: the street tracker's measurement tables.

Made from the run files ``python -m experiments.fusion_runs`` writes into
experiments/results/fusion/ (one per scenario, hour, seed and fidelity). For each scenario: every
1,200 s run at full fidelity and in fast mode (share of the oracle's savings / lit on entry per
controller), the runs pooled against the issue's targets, the split of the gap to the oracle, fast
mode against full fidelity run by run, and a whole fast night.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

from citysim.report.common import fmt_pct
from citysim.sim.validation import compare_figures
from experiments.fusion_runs import NIGHT_HOURS, SCENARIOS, SEEDS, run_name, start_clock
from experiments.results.sources import FUSION

SHOWN = ("oracle_seen", "pir", "detector_located", "detector_fused")
#: The issue's targets for detector_fused, the six full-fidelity runs pooled.
TARGET_SHARE = 0.90
TARGET_LIT = 0.99


def _runs(n: int) -> str:
    return f"{n} run" if n == 1 else f"{n} runs"


def load_runs(results_dir: Path, scenario: str, fidelity: str) -> list[dict]:
    """The scenario's 1,200 s runs in ``fidelity`` that exist, in table order (22:00 seeds 1-3, then 02:00),
    each with its ``start`` clock time."""
    runs = []
    for hour in NIGHT_HOURS:
        for seed in SEEDS:
            path = results_dir / FUSION.file / f"{run_name(scenario, hour, seed, fidelity)}.json"
            if path.exists():
                runs.append({"start": start_clock(hour), **json.loads(path.read_text())})
    return runs


def pooled(runs: Sequence[Mapping], label: str) -> dict:
    """One controller over ``runs``: share of the oracle's savings (its mean savings over the oracle's,
    which is saved energy over saved energy: every run has the same lamps and length), lit on entry
    (entries lit over entries), entries and the mean gap split."""
    oracle = sum(r["controllers"]["oracle"]["savings_vs_always_on"] for r in runs)
    own = sum(r["controllers"][label]["savings_vs_always_on"] for r in runs)
    cells = [r["controllers"][label] for r in runs]
    entries = sum(c["zone_entries"] or 0 for c in cells)
    lit = sum((c["lit_on_entry_rate"] or 0.0) * (c["zone_entries"] or 0) for c in cells)

    def mean(key: str) -> float | None:
        values = [c[key] for c in cells if c.get(key) is not None]
        return sum(values) / len(values) if values else None

    return {"share": own / oracle if oracle else None, "lit": lit / entries if entries else None,
            "entries": entries, "gap_unseen": mean("gap_unseen"), "gap_unused": mean("gap_unused"),
            "dark_unseen": mean("dark_unseen"), "dark_unused": mean("dark_unused")}  # fmt: skip


def _cell(c: Mapping) -> str:
    share = c.get("savings_vs_oracle")
    return f"{'-' if share is None else f'{share:.2f}'} / {fmt_pct(c.get('lit_on_entry_rate'))}"


def run_table(runs: Sequence[Mapping]) -> list[str]:
    """One row per run: oracle savings, then share of the oracle's savings / lit on entry per controller."""
    lines = ["| start | seed | entries | oracle savings | " + " | ".join(SHOWN) + " | CPU-min |",
             "|---|---|---|---|" + "---|" * len(SHOWN) + "---|"]  # fmt: skip
    for r in runs:
        c = r["controllers"]
        cells = " | ".join(_cell(c[label]) for label in SHOWN)
        lines.append(f"| {r['start']} | {r['seed']} | {c['oracle']['zone_entries']} | "
                     f"{fmt_pct(c['oracle']['savings_vs_always_on'])} | {cells} | {r['cpu_s'] / 60:.1f} |")
    return lines


def pooled_lines(runs: Sequence[Mapping]) -> list[str]:
    """The runs pooled per controller, detector_fused against the targets, and the gap split."""
    stats = {label: pooled(runs, label) for label in SHOWN}
    fused = stats["detector_fused"]
    share_ok = fused["share"] is not None and fused["share"] >= TARGET_SHARE
    lit_ok = fused["lit"] is not None and fused["lit"] >= TARGET_LIT
    rows = ", ".join(f"{label} {p['share']:.3f} at {fmt_pct(p['lit'])}" for label, p in stats.items())
    split = "; ".join(
        f"{label} {100 * p['gap_unused']:+.1f} points of the oracle's savings and {100 * p['dark_unused']:+.1f} of "
        f"entries" for label in ("detector_located", "detector_fused") for p in [stats[label]]
        if p["gap_unused"] is not None and p["dark_unused"] is not None)  # fmt: skip
    unseen = stats["oracle_seen"]
    return [
        f"Pooled over the {_runs(len(runs))} ({fused['entries']} zone entries): {rows} (share of the oracle's "
        f"savings at lit on entry).",
        f"Target for detector_fused: >= {TARGET_SHARE:.2f} of the oracle's savings "
        f"({'met' if share_ok else 'missed'}: {fused['share']:.3f}) with >= {fmt_pct(TARGET_LIT, 0)} lit on entry "
        f"({'met' if lit_ok else 'missed'}: {fmt_pct(fused['lit'])}).",
        f"The gap split, mean per run: no camera can see {100 * (unseen['gap_unseen'] or 0):+.1f} points of the "
        f"oracle's savings and {100 * (unseen['dark_unseen'] or 0):.1f} % of entries; the cameras saw and the "
        f"controller did not use: {split}.",
    ]


def agreement_lines(full: Sequence[Mapping], fast: Sequence[Mapping]) -> list[str]:
    """Fast mode against full fidelity on the runs both have, per controller (``citysim validate``'s rule)."""
    pairs = {(r["start"], r["seed"]): r for r in fast}
    matched = [(r, pairs[(r["start"], r["seed"])]) for r in full if (r["start"], r["seed"]) in pairs]
    if not matched:
        return ["Fast mode against full fidelity: no run measured both ways."]
    figures = compare_figures([m[0] for m in matched], [m[1] for m in matched])
    lines = [f"Fast mode against full fidelity, the same {_runs(len(matched))} (seeds 1-3, no calibration seed), "
             "means over the runs (`citysim validate`'s tolerances: savings within 2 points, lit on entry within "
             "1 point):", "",
             "| controller | savings full / fast | lit on entry full / fast |", "|---|---|---|"]  # fmt: skip
    for label in SHOWN:
        row = figures[label]
        cells = []
        for name in ("savings", "lit_on_entry"):
            c = row[name]
            mark = "agrees" if c["pass"] else f"misses by {100 * (abs(c['diff']) - c['tolerance']):.1f} points"
            cells.append(f"{fmt_pct(c['full'])} / {fmt_pct(c['fast'])} ({mark})")
        lines.append(f"| {label} | {cells[0]} | {cells[1]} |")
    return lines


def night_line(results_dir: Path, scenario: str) -> str:
    """The whole fast night (22:00-06:00) of the scenario, one sentence."""
    path = results_dir / FUSION.file / f"{run_name(scenario, None, SEEDS[0], 'fast')}.json"
    if not path.exists():
        return "The whole fast night: not measured."
    run = json.loads(path.read_text())
    c = run["controllers"]
    cells = ", ".join(f"{label} {_cell(c[label])}" for label in SHOWN)
    return (f"The whole night in fast mode (22:00-06:00, seed 1, {c['oracle']['zone_entries']} zone entries, "
            f"{run['cpu_s'] / 60:.1f} CPU-min): the oracle saves {fmt_pct(c['oracle']['savings_vs_always_on'])}; "
            f"{cells} (share of the oracle's savings / lit on entry).")


def fusion_section(results_dir: Path) -> str:
    """docs/design/fusion.md's generated measurement tables."""
    out = [f"Made by `{FUSION.command}` (one file per run in `experiments/results/{FUSION.file}/`). Each run: "
           "`always_on, oracle, oracle_seen, pir, detector_located, detector_fused` on the same traffic, 1,200 s "
           "from 22:00 (the night's first hour) or from 02:00 (its fifth, `experiments.bench.night.night_hour`). "
           "Cells: share of the oracle's savings / lit on entry.", ""]  # fmt: skip
    for scenario in SCENARIOS:
        full, fast = load_runs(results_dir, scenario, "full"), load_runs(results_dir, scenario, "fast")
        out += [f"### {scenario}", "", "**Full fidelity** (every judged frame rendered and detected):", ""]
        out += (run_table(full) + [""] + pooled_lines(full) if full else ["Not measured."]) + [""]
        out += ["**Fast mode** (the shipped sensor model):", ""]
        out += (run_table(fast) + [""] + pooled_lines(fast) if fast else ["Not measured."]) + [""]
        out += agreement_lines(full, fast) + ["", night_line(results_dir, scenario), ""]
    return "\n".join(out).rstrip() + "\n"


def fusion_summary_section(results_dir: Path) -> str:
    """docs/guide/fusion.md's generated summary: each scenario's full-fidelity runs pooled, one sentence."""
    lines = []
    for scenario in SCENARIOS:
        runs = load_runs(results_dir, scenario, "full")
        if not runs:
            lines.append(f"- {scenario}: not measured.")
            continue
        cells = "; ".join(f"{label} {p['share']:.2f} of the oracle's savings at {fmt_pct(p['lit'])} lit on entry"
                          for label in SHOWN[1:] for p in [pooled(runs, label)])  # fmt: skip
        oracle = sum(r["controllers"]["oracle"]["savings_vs_always_on"] for r in runs) / len(runs)
        lines.append(f"- **{scenario}** ({_runs(len(runs))} of 1,200 s at full fidelity, "
                     f"{pooled(runs, 'oracle')['entries']} zone entries; the oracle saves {fmt_pct(oracle)} "
                     f"of always-on's energy on average): {cells}.")
    return (f"Measured by `{FUSION.command}` (every run, fast mode beside full fidelity and the whole nights: "
            "[design: fusion](../design/fusion.md#measurements)):\n\n" + "\n".join(lines) + "\n")
