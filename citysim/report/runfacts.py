"""What a run folder says beyond its figures: its clock window, the objects behind it, the never-lit
crossings, and the sentences that put the figures in context.

Reads only the run folder (summary.json, objects.csv, lamps.csv) and, where summary.json names
it (``scenario_file``) and it is still there, the scenario file: its start hour, hold time and
schedule steps. Whatever cannot be found is said to be unknown rather than guessed.

Used by ``run_plots`` (clock axes, object counts in legends, the few-objects warning) and by
``html`` (the window line, the zero-savings reasons, the per-frame detection reading).
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

from citysim.report.common import (
    FEW_OBJECTS,
    TARGET_CLASSES,
    PlotError,
    clock_text,
    few_objects_text,
    fmt_num,
    fmt_pct,
    read_csv,
    to_float,
)

__all__ = [
    "DETECTION_HEAD",
    "RunFacts",
    "detection_figures",
    "detection_row",
    "detection_sentence",
    "load_summary",
    "read_passages",
    "run_facts",
    "zero_savings_reasons",
]

REFERENCE = "always_on"
#: objects.csv rounds times to 1 ms, so lag and stay of a never-lit crossing differ by up to ~1.5 ms
NEVER_LIT_TOLERANCE_S = 0.002
#: |savings| below this counts as "saves nothing" (0.0 % as printed)
ZERO_SAVINGS = 0.0005


def load_summary(run_dir: Path) -> dict:
    path = run_dir / "summary.json"
    if not path.exists():
        raise PlotError(f"{run_dir}: no summary.json; not a run folder written by `citysim run`")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise PlotError(f"{path}: not valid JSON ({exc})") from None


def is_never_lit(lag_s: float, stay_s: float, lit_on_entry: float) -> bool:
    """A crossing whose lamp never reached its level while the object was in the zone.

    objects.csv has no 'lit' column: the simulator writes such a crossing's lag as its whole stay
    (entry to exit) and lit_on_entry 0, which is how it is recognised here.
    """
    if lit_on_entry == 1 or math.isnan(lag_s) or math.isnan(stay_s) or stay_s <= 0:
        return False
    return lag_s >= stay_s - NEVER_LIT_TOLERANCE_S


def read_passages(path: Path) -> list[dict]:
    """objects.csv rows with numbers parsed and ``never_lit`` set (empty list if the file is missing)."""
    if not path.exists():
        return []
    out = []
    for r in read_csv(path):
        t_enter, t_exit, lag = to_float(r["t_enter_s"]), to_float(r["t_exit_s"]), to_float(r["lag_s"])
        lit_on_entry = to_float(r.get("lit_on_entry"))
        out.append({
            "controller": r["controller"], "object_id": r["object_id"], "cls": r["cls"],
            "lamp": int(r["lamp"]), "t_enter_s": t_enter, "t_exit_s": t_exit, "lag_s": lag,
            "dark_s": to_float(r.get("dark_s")), "lit_on_entry": lit_on_entry == 1,
            "never_lit": is_never_lit(lag, t_exit - t_enter, lit_on_entry),
        })  # fmt: skip
    return out


def load_scenario_of(summary: dict):
    """The scenario named by summary.json's scenario_file, or (None, why not).

    The path is as the run was given it (often relative to the folder ``citysim run`` ran in).
    """
    source = summary.get("scenario_file")
    if not source:
        return None, "summary.json names no scenario file"
    if not Path(source).is_file():
        return None, f"scenario file {source} not found from {Path.cwd()}"
    from citysim.config.scenario import ScenarioError, load_scenario

    try:
        return load_scenario(source), None
    except ScenarioError as exc:
        return None, f"scenario file {source} does not load ({exc})"


@dataclass
class RunFacts:
    """The run's window on the night and the objects it saw (every controller sees the same traffic)."""

    scenario_name: str
    duration_s: float
    start_hour: float | None
    scenario: object | None = None  # citysim.config.scenario.Scenario when its file was found
    scenario_note: str | None = None  # why the scenario is unknown
    objects: int | None = None  # distinct target objects that crossed a lamp zone
    objects_by_class: dict[str, int] = field(default_factory=dict)
    zone_entries: int = 0

    @property
    def few_objects(self) -> bool:
        return self.objects is not None and self.objects < FEW_OBJECTS

    def clock_span(self) -> str | None:
        """'22:00-22:05' (None when the start hour is unknown)."""
        if self.start_hour is None:
            return None
        seconds = self.duration_s % 60 != 0
        return (f"{clock_text(self.start_hour, 0.0, seconds)}-"
                f"{clock_text(self.start_hour, self.duration_s, seconds)}")  # fmt: skip

    def window_line(self) -> str:
        """One sentence: which clock hours the run covers and how many objects it saw."""
        span = self.clock_span()
        minutes = fmt_num(self.duration_s / 60.0)
        when = (f"This run covers {span} ({minutes} min of simulated night from the scenario's "
                f"{clock_text(self.start_hour, 0.0)} start)" if span else
                f"This run covers {minutes} min of simulated night (clock hours unknown: "
                f"{self.scenario_note or 'no start hour'})")  # fmt: skip
        if self.objects is None:
            return when + "; objects.csv is missing, so the objects seen are unknown."
        classes = ", ".join(f"{n} {c}{'s' if n != 1 else ''}"
                            for c, n in self.objects_by_class.items() if n)  # fmt: skip
        seen = (f"{self.objects} object{'s' if self.objects != 1 else ''} crossed a lamp zone"
                + (f" ({classes}; {self.zone_entries} zone entries)" if classes else ""))  # fmt: skip
        return f"{when}; {seen}."

    def warning(self) -> str | None:
        """The few-objects warning as a sentence, or None when the run saw enough objects."""
        if not self.few_objects:
            return None
        return (few_objects_text(self.objects) + ": one crossing more or less lit moves their "
                "percentages by several points. Run longer (citysim run --duration) before "
                "drawing conclusions.")  # fmt: skip


def run_facts(run_dir: Path, summary: dict, passages: list[dict]) -> RunFacts:
    """The facts of a run folder; ``passages`` are its objects.csv rows (``read_passages``)."""
    scenario, note = load_scenario_of(summary)
    start_hour = summary.get("start_hour")
    if start_hour is None and scenario is not None:
        start_hour = scenario.start_hour
    facts = RunFacts(str(summary.get("scenario", "")), float(summary.get("duration_s") or 0.0),
                     None if start_hour is None else float(start_hour), scenario, note)  # fmt: skip
    names = list(summary.get("controllers", {}))
    if not (run_dir / "objects.csv").exists() or not names:
        return facts
    reference = names[0]  # every controller sees the same traffic
    shown = [p for p in passages if p["controller"] == reference and p["cls"] in TARGET_CLASSES]
    by_class: dict[str, set] = defaultdict(set)
    for p in shown:
        by_class[p["cls"]].add(p["object_id"])
    facts.objects = len({p["object_id"] for p in shown})
    facts.objects_by_class = {c: len(by_class[c]) for c in TARGET_CLASSES if by_class.get(c)}
    facts.zone_entries = len(shown)
    return facts


def _controller_spec(facts: RunFacts, name: str):
    """The scenario's spec for a controller label, as the run resolved it (its registry defaults
    when the scenario does not list it); None without the scenario.

    Not ``citysim.sim.loop.controller_spec``: sim imports the run plots, and the report would
    import it back.
    """
    if facts.scenario is None:
        return None
    from citysim.config.scenario import ControllerSpec

    for spec in facts.scenario.controllers:
        if name in (spec.display_name, spec.name):
            return spec
    return ControllerSpec(name=name)


def _schedule_reason(facts: RunFacts, name: str) -> str | None:
    """Why a schedule controller kept full level: its steps, read through the controller itself."""
    spec = _controller_spec(facts, name)
    if spec is None or spec.name != "schedule" or facts.start_hour is None:
        return None
    from citysim.control.clock import ScheduleSteps

    schedule = ScheduleSteps.of(spec, facts.scenario.lamps.luminaire.dim_level)
    # the level in force at each minute of the window (steps start on clock hours or fractions)
    minutes = range(0, int(facts.duration_s // 60) + 1)
    levels = {schedule.level_at_hour((facts.start_hour + m / 60.0) % 24.0) for m in minutes}
    if min(levels) < 1.0:
        return None
    # in clock order from the run's start: 22:00 full, 00:00 50 %, 05:00 full
    ordered = sorted(schedule.steps, key=lambda step: (step[0] - facts.start_hour) % 24.0)
    steps = ", ".join(f"{clock_text(h, 0.0)} {'full' if level >= 1.0 else fmt_pct(level, 0)}"
                      for h, level in ordered)  # fmt: skip
    dims = [h for h, level in ordered if level < 1.0]
    first_dim = (f"it dims only from {clock_text(dims[0], 0.0)}, after this window ends"
                 if dims else "none of its steps dims")  # fmt: skip
    return (f"{name} saves 0 % because of this window, not because it cannot save: its steps "
            f"({steps}) keep the lamps at full over {facts.clock_span()}, and "
            f"{first_dim}. A run past that hour shows its savings.")  # fmt: skip


def _full_all_window(lamps_csv: Path, name: str) -> bool | None:
    """True if every lamp of ``name`` stayed at full level for the whole run (None: no lamps.csv)."""
    if not lamps_csv.exists():
        return None
    rows = (r for r in read_csv(lamps_csv) if r["controller"] == name)
    return all(to_float(r["level"]) >= 1.0 for r in rows)


def zero_savings_reasons(run_dir: Path, summary: dict, facts: RunFacts) -> dict[str, str]:
    """controller -> why it saves 0 %, for every controller but always_on that saves nothing."""
    out = {}
    for name, f in summary.get("controllers", {}).items():
        savings = f.get("savings_vs_always_on")
        if name == REFERENCE or savings is None or abs(savings) >= ZERO_SAVINGS:
            continue
        reason = _schedule_reason(facts, name)
        if reason is None and _full_all_window(run_dir / "lamps.csv", name):
            reason = (f"{name} saves 0 %: its lamps stayed at full level for the whole window "
                      f"({facts.clock_span() or fmt_num(facts.duration_s) + ' s'}), as always-on's do.")  # fmt: skip
        out[name] = reason or f"{name} saves 0 % in this window."
    return out


def _hold_s(facts: RunFacts, name: str) -> float | None:
    spec = _controller_spec(facts, name)
    if spec is None:
        return None
    return spec.hold_s if spec.hold_s is not None else facts.scenario.lamps.luminaire.hold_s


#: Columns of the report's detection table (``detection_row``).
DETECTION_HEAD = ["controller", "per-frame TPR", "precision", "judged frames per pass",
                  "passes with no detection", "zone entries lit while inside", "lit on entry"]  # fmt: skip


def detection_figures(name: str, figures: dict, passages: list[dict]) -> dict | None:
    """A camera controller's per-frame detection figures beside its zone crossings (None: no camera)."""
    det = figures.get("detection") or {}
    if not det.get("frames"):
        return None
    passes = det.get("object_passes") or 0
    target_frames = (det.get("tp") or 0) + (det.get("fn") or 0)
    mine = [p for p in passages if p["controller"] == name and p["cls"] in TARGET_CLASSES]
    return {"name": name, "tpr": det.get("tpr"), "precision": det.get("precision"),
            "frames_per_pass": target_frames / passes if passes else None, "passes": passes,
            "missed": det.get("missed_passes"), "miss_rate": det.get("miss_rate"),
            "entries": len(mine), "lit": sum(not p["never_lit"] for p in mine),
            "on_entry": sum(bool(p["lit_on_entry"]) for p in mine)}  # fmt: skip


def detection_row(f: dict) -> list[str]:
    """``detection_figures`` as a row under DETECTION_HEAD."""

    def of(k: int | None, n: int) -> str:
        return "-" if k is None or not n else f"{k} of {n} ({fmt_pct(k / n)})"

    return [f["name"], fmt_pct(f["tpr"]), fmt_pct(f["precision"]), fmt_num(f["frames_per_pass"], 2),
            of(f["missed"], f["passes"]), of(f["lit"], f["entries"]), of(f["on_entry"], f["entries"])]  # fmt: skip


def _span(values: list[float], fmt) -> str:
    lo, hi = min(values), max(values)
    return fmt(lo) if fmt(lo) == fmt(hi) else f"{fmt(lo)} to {fmt(hi)}"


def detection_sentence(found: list[dict], facts: RunFacts) -> str:
    """Why a low per-frame true-positive rate still lights lamps in time, with this run's numbers."""
    holds = {_hold_s(facts, f["name"]) for f in found}
    hold = (f"its {fmt_num(holds.pop())} s hold time" if len(holds) == 1 and None not in holds
            else "its hold time")  # fmt: skip
    tprs = [f["tpr"] for f in found if f["tpr"] is not None]
    frames = [f["frames_per_pass"] for f in found if f["frames_per_pass"] is not None]
    text = "The per-frame figures count camera frames, not people"
    if tprs:
        text += f": the detector found {_span(tprs, fmt_pct)} of the targets in view frame by frame"
    if frames:
        text += (f", but each pass of an object through a camera's view gives about "
                 f"{_span(frames, lambda v: fmt_num(v, 2))} judged frames")  # fmt: skip
    return (text + f", and one detection keeps a lamp lit for {hold}, so a low per-frame rate "
            "still lights lamps in time. What counts for people are the last two columns: zone "
            "entries lit while the object was inside, and lit already on entry.")
