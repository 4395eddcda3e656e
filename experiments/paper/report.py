"""The reproduction's Markdown report: each of our numbers beside the paper's.

``PAPER`` holds the figures the paper states in its text (section 6.2, section
7, section 8.1, Tables 2-4); ``write_markdown`` lays ours beside them in
tables, with the prose of ``experiments.paper.notes`` (what was measured how,
and why the two differ).
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

from detector.classes import CLASSES
from experiments.paper.metrics import Confusions
from experiments.paper.notes import (
    BASELINE_NOTES,
    DEFINITIONS,
    baseline_reading,
    fmt,
    paper_target_share,
    what_differs,
    window_reading,
)
from experiments.paper.scenes import PAPER_SCENES
from experiments.paper.tracks import MIN_OBJECT_FRAMES

if TYPE_CHECKING:
    from experiments.paper.results import ConditionResult, Reproduction

#: Figures stated in the paper's text (Figs. 9-10 are only described through these).
PAPER = {
    "night_fnr": 0.24, "night_fpr": 0.03, "day_tpr": 0.96, "day_fpr": 0.05,
    "night_cyclist_tpr": 0.48, "night_group_tpr": 0.44,
    "pedestrian_to_group": 0.32, "vehicle_to_noise": 0.25,
    "night_binary_ap": 0.93, "day_binary_ap": 0.99,
    "night_macro_ap": 0.67, "day_macro_ap": 0.84,
    "night_pedestrian_ap": 0.80, "night_group_ap": 0.36,
    "eq12_p": 0.76, "eq12_window": 0.90,
    "threshold_5_tpr": 0.20, "threshold_05_fpr": 0.90,
}  # fmt: skip
TRACK_NOTES = (
    "The detector follows each object across frames (`detector.tracks`) and decides per track: "
    "a track is a target when a road user could have made it (speed, acceleration, size steady "
    "within Table 1, no wider than a cyclist's or a car's front or back when it goes faster than "
    "walkers along the line of sight, a few frames seen and its motion known) and its class "
    "probabilities pooled over its last 15 frames say target, or when it moves like a vehicle "
    "going away (straight, steady, 5-20 m/s: a car seen from behind, often only its headlight "
    "spot). *frames*: the 'objects' rows above, decided by the detection's track. "
    f"*objects*: targets eligible in at least {MIN_OBJECT_FRAMES} frames; *missed*: no detection "
    "matched to it was a target in any of them. *noise tracks*: tracks whose detections mostly "
    "match no target; *called target*: a target in at least one frame; *clean* leaves out noise "
    "tracks lying mostly on a target's box (pieces of road users). The per-frame row counts the "
    "same objects and tracks with each frame's own decision. The pooling rows recompute the "
    "decisions from the same detections with another pooling (plausibility unchanged)."
)
#: Table 3: frames/s (min, mean, max) per board; Table 4 gives the Pi 3 B 35 fps at 25 % CPU.
PAPER_FPS = {
    "Beaglebone Black (Cortex-A8 1 GHz)": (4, 5, 7),
    "Orange Pi PC (4x Cortex-A7 1.4 GHz)": (10, 13, 15),
    "Orange Pi Zero H5 (4x Cortex-A53 1.4 GHz)": (25, 28, 35),
    "Raspberry Pi 3 Model B+ (4x Cortex-A53 1.4 GHz)": (30, 35, 40),
}


def _diff(ours: float | None, paper: float) -> str:
    if ours is None:
        return "-"
    return f"{ours - paper:+.2f}"


def _table(header: Iterable[str], rows: Iterable[Iterable[object]]) -> list[str]:
    header = list(header)
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return lines + [""]


def _matrix_table(conf: Confusions) -> list[str]:
    rates, counts = conf.five, conf.five_counts
    header = ["truth \\ predicted", *CLASSES, "instances"]
    rows = []
    for i, cls in enumerate(CLASSES):
        n = int(counts[i].sum())
        rows.append([cls, *(fmt(rates[i, j]) if n else "-" for j in range(len(CLASSES))), n])
    return _table(header, rows)


def _setup(rep: Reproduction) -> list[str]:
    rows = []
    for s in rep.scenes.values():
        r = s.records
        noise = sum(1 for c, d in zip(r.truth_cls, r.detected, strict=True) if d and c == "noise")
        inst = "/".join(str(r.truth_instances.get(c, 0)) for c in CLASSES[1:])
        table2 = "/".join(str(PAPER_SCENES[s.key].table2_counts[c]) for c in CLASSES)
        rows.append([s.key, s.title, s.resolution, f"{s.range_m:g}", r.frames, noise, inst, table2])
    return _table(
        ["scene", "paper scene", "camera", "range m", "scored frames", "noise regions",
         "targets P/G/C/V", "paper Table 2 N/P/G/C/V"],
        rows,
    )  # fmt: skip


#: Column titles of the row sets (``paper_metrics.VARIANTS``).
VARIANT_TITLES = {
    "objects": "objects",
    "regions": "regions only",
    "clean": "regions, fragments out",
}


def _ours(cond: ConditionResult, value) -> list[str]:
    """``value(confusions)`` for every variant of ``cond``, formatted."""
    return [fmt(value(cond.confusions[v])) for v in VARIANT_TITLES]


def _binary(night: ConditionResult, day: ConditionResult) -> list[str]:
    def row(name, cond, paper, value):
        return [name, paper, *_ours(cond, value), _diff(value(cond.confusions["objects"]), paper)]

    rows = [
        row("night FNR (targets called noise)", night, PAPER["night_fnr"], lambda c: 1 - c.tpr),
        row("night FPR (noise called target)", night, PAPER["night_fpr"], lambda c: c.fpr),
        row("day TPR", day, PAPER["day_tpr"], lambda c: c.tpr),
        row("day FPR", day, PAPER["day_fpr"], lambda c: c.fpr),
    ]
    titles = [f"ours: {t}" for t in VARIANT_TITLES.values()]
    return _table(["Fig. 9a-b", "paper", *titles, "objects - paper"], rows)


def _five(night: ConditionResult, day: ConditionResult) -> list[str]:
    cells = [
        ("night cyclist TPR", night, "night_cyclist_tpr", ("cyclist", "cyclist")),
        ("night group TPR", night, "night_group_tpr", ("group", "group")),
        ("pedestrian -> group, night", night, "pedestrian_to_group", ("pedestrian", "group")),
        ("pedestrian -> group, day", day, "pedestrian_to_group", ("pedestrian", "group")),
        ("vehicle -> noise, night", night, "vehicle_to_noise", ("vehicle", "noise")),
        ("vehicle -> noise, day", day, "vehicle_to_noise", ("vehicle", "noise")),
    ]
    rows = [[name, PAPER[key], *_ours(cond, lambda c, t=cell: c.rate(*t))]
            for name, cond, key, cell in cells]  # fmt: skip
    return _table(["Fig. 9c-d", "paper", *(f"ours: {t}" for t in VARIANT_TITLES.values())], rows)


def _pr(night: ConditionResult, day: ConditionResult) -> list[str]:
    def aps(cond, value):
        return [fmt(value(cond.precision_recall[v])) for v in VARIANT_TITLES]

    paper_chance = {c: paper_target_share(c) for c in ("night", "day")}
    rows = [
        ["night binary AP", PAPER["night_binary_ap"], *aps(night, lambda p: p.binary.ap)],
        ["night binary AP of chance (share of targets)", fmt(paper_chance["night"]), *aps(night, lambda p: p.binary.chance_ap)],
        ["day binary AP", PAPER["day_binary_ap"], *aps(day, lambda p: p.binary.ap)],
        ["day binary AP of chance (share of targets)", fmt(paper_chance["day"]), *aps(day, lambda p: p.binary.chance_ap)],
        ["night macro mAP (5 classes)", PAPER["night_macro_ap"], *aps(night, lambda p: p.macro_ap)],
        ["day macro mAP (5 classes)", PAPER["day_macro_ap"], *aps(day, lambda p: p.macro_ap)],
        ["night pedestrian AP", PAPER["night_pedestrian_ap"], *aps(night, lambda p: p.ap("pedestrian"))],
        ["night group AP", PAPER["night_group_ap"], *aps(night, lambda p: p.ap("group"))],
        ["night micro AP", "(curve only)", *aps(night, lambda p: p.micro.ap)],
        ["day micro AP", "(curve only)", *aps(day, lambda p: p.micro.ap)],
    ]  # fmt: skip
    for cond, classes in ((night, ("noise", "cyclist", "vehicle")), (day, CLASSES)):
        for cls in classes:
            rows.append([f"{cond.name} {cls} AP", "-", *aps(cond, lambda p, c=cls: p.ap(c))])
    titles = [f"ours: {t}" for t in VARIANT_TITLES.values()]
    return _table(["Fig. 10", "paper", *titles], rows)


def _distance(night: ConditionResult, day: ConditionResult) -> list[str]:
    rows = []
    for n, d in zip(night.by_distance, day.by_distance, strict=True):
        rows.append([f"{n.lo_m:g}-{n.hi_m:g} m", n.targets, fmt(n.tpr), fmt(n.missed),
                     d.targets, fmt(d.tpr), fmt(d.missed)])  # fmt: skip
    return _table(["object distance", "night targets", "night TPR", "night not segmented",
                   "day targets", "day TPR", "day not segmented"], rows)  # fmt: skip


def _baseline(night: ConditionResult, day: ConditionResult) -> list[str]:
    rows = []
    for cond in (night, day):
        for frac, b in cond.baseline.items():
            paper = {
                0.05: f"TPR {PAPER['threshold_5_tpr']}",
                0.005: f"FPR {PAPER['threshold_05_fpr']}",
            }
            rows.append([
                cond.name, f"{100 * frac:g} %", paper.get(frac, "-") if cond.name == "night" else "-",
                fmt(b.tpr), fmt(b.fpr), fmt(b.frame_tpr), fmt(b.frame_fpr),
                f"{b.target_instances} / {b.noise_regions} / {b.target_frames} / {b.empty_frames}",
            ])  # fmt: skip
    return _table(
        ["data", "threshold (of frame)", "paper (night)", "TPR per instance", "FPR per region",
         "TPR per frame", "FPR per empty frame", "targets / noise regions / target frames / empty frames"],
        rows,
    )  # fmt: skip


def _window(night: ConditionResult, day: ConditionResult) -> list[str]:
    rows = [["paper, night", fmt(PAPER["eq12_p"]), fmt(PAPER["eq12_window"]), "-", "-"]]
    for cond in (night, day):
        w = cond.window
        rows.append(
            [f"ours, {cond.name}", fmt(w.p_frame), fmt(w.predicted), fmt(w.measured), w.windows]
        )
    return _table(
        ["", "per-frame TPR p", "eq. 12, n = 5", "measured over 5-frame windows", "windows"], rows
    )


def _speed(rep: Reproduction) -> list[str]:
    rows = [[f"ours: scene {s.key}, {s.resolution}", rep.cpu, fmt(s.detector_fps_cpu, 0),
             fmt(s.detector_fps_wall, 0), s.records.detector_frames]
            for s in rep.scenes.values()]  # fmt: skip
    for board, (lo, mean, hi) in PAPER_FPS.items():
        rows.append([f"paper Table 3: {board}", "-", f"{mean} (min {lo}, max {hi})", "-", "-"])
    rows.append(["paper Table 4: Raspberry Pi 3 B", "-", "35 at 25 % CPU", "-", "-"])
    return _table(["", "CPU", "frames/s (CPU time)", "frames/s (wall clock)", "frames"], rows)


TRACK_DECISIONS = {
    "per frame": "each frame's own P(target) (today's rule)",
    "run": "tracks, as run (mean log-probabilities)",
    "mean_log": "tracks, pooled: mean log-probabilities",
    "mean": "tracks, pooled: mean probabilities",
    "last": "tracks, pooled: last frame only",
}


def _tracks(night: ConditionResult, day: ConditionResult) -> list[str]:
    rows = []
    for cond in (night, day):
        for key, title in TRACK_DECISIONS.items():
            f = cond.tracks[key]
            rows.append([cond.name, title, fmt(f.frame_fnr), fmt(f.frame_fpr), f.objects, fmt(f.object_miss),
                         f.noise_tracks, fmt(f.track_fpr), f.clean_noise_tracks, fmt(f.clean_track_fpr)])
    header = ["condition", "decision", "frames: FNR", "frames: FPR", "objects", "objects missed",
              "noise tracks", "called target", "clean noise tracks", "called target (clean)"]  # fmt: skip
    return _table(header, rows)


def _per_scene(rep: Reproduction) -> list[str]:
    rows = []
    for s in rep.scenes.values():
        c = s.confusions
        rows.append(
            [
                s.key,
                s.time_of_day,
                fmt(c.tpr),
                fmt(c.fpr),
                int(c.binary_counts[1].sum()),
                int(c.binary_counts[0].sum()),
            ]
        )
    return _table(["scene", "time", "TPR", "FPR", "target rows", "noise rows"], rows)


def write_markdown(rep: Reproduction, path: Path) -> Path:
    """Write the report to ``path``; returns it."""
    night, day = rep.conditions["night"], rep.conditions["day"]
    b = rep.budget
    lines = ["# Reproducing Matveev et al. (Sensors 2020) on simulated scenes A-D", ""]
    if rep.quick:
        lines += [
            "> **Quick mode**: a few seconds per scene; the numbers below are a smoke test, not results.",
            "",
        ]
    lines += [
        "Generated by `python -m experiments.paper.reproduce`"
        f"{' --quick' if rep.quick else ''} at commit {rep.source}; do not edit by hand. "
        "Each scene's traffic runs alone "
        f"for {b.preroll_s:g} s, then the camera films; the first {b.warmup_s:g} s of frames only "
        "train the background model. Night = scenes "
        f"{', '.join(night.scenes)} pooled; day = scene {', '.join(day.scenes)}. Figures: "
        f"[{rep.files['confusion'].name}]({rep.files['confusion'].name}) (Fig. 9), "
        f"[{rep.files['precision_recall'].name}]({rep.files['precision_recall'].name}) (Fig. 10).",
        "",
        "## Scenes (Table 2)",
        "",
        *_setup(rep),
        DEFINITIONS,
        "## Fig. 9: target vs noise",
        "",
        *_binary(night, day),
        "By the object's distance (objects; *not segmented*: no detection matched it):",
        "",
        *_distance(night, day),
        "Per scene (objects):",
        "",
        *_per_scene(rep),
        "## Fig. 9: five classes",
        "",
        "The paper does not say from which panel (night or day) its pedestrian -> group and "
        "vehicle -> noise rates come; both are shown.",
        "",
        *_five(night, day),
        "Night, objects (row-normalised):",
        "",
        *_matrix_table(night.confusions["objects"]),
        "Day, objects (row-normalised):",
        "",
        *_matrix_table(day.confusions["objects"]),
        "## Fig. 10: precision-recall",
        "",
        *_pr(night, day),
        "## Section 7: the naive threshold baseline",
        "",
        BASELINE_NOTES,
        *_baseline(night, day),
        baseline_reading(night),
        "## Section 8.1, eq. 12: deciding over five frames",
        "",
        "Eq. 12 assumes independent frames. *Measured*: for every target, every run of five "
        "consecutive frames in which it was fully in view within range, whether it was detected "
        "as a target in at least three.",
        "",
        *_window(night, day),
        window_reading(night),
        window_reading(day),
        "## Per object, with tracks (section 8)",
        "",
        TRACK_NOTES,
        "",
        *_tracks(night, day),
        "## Tables 3-4: speed",
        "",
        *_speed(rep),
        what_differs(night, day),
    ]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines))
    return path
