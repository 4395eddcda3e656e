"""Reproduce the paper's evaluation (section 6.2, section 7, Tables 3-4) on simulated scenes A-D.

    python -m experiments.paper.reproduce            # the full run (a few minutes)
    python -m experiments.paper.reproduce --quick    # seconds: a tiny budget per scene

Films the replicas of the paper's scenes (``experiments.paper.scenes``), runs
the real detector on every frame, pools night (A-C) and day (D) as the paper
does, and writes to ``--out`` (default ``experiments/results``; ``--quick``
defaults to ``experiments/results/quick``):

* ``paper_comparison.md``: each of our numbers beside the paper's, with what
  differs and why (``experiments.paper.report``);
* ``paper_confusion.png`` (Fig. 9) and ``paper_precision_recall.png`` (Fig. 10).

The detector is timed single-threaded (``cv2.setNumThreads(1)``, process CPU
time around ``Detector.process`` only), like the paper's implementation.
"""

from __future__ import annotations

import argparse
import platform
import subprocess
import sys
from pathlib import Path

import cv2
from tqdm import tqdm

from experiments.paper.metrics import (
    VARIANTS,
    Rows,
    confusions,
    precision_recall,
    threshold_baseline,
    tpr_by_distance,
    window_detection,
)
from experiments.paper.notes import fmt
from experiments.paper.plots import plot_confusions, plot_precision_recall
from experiments.paper.report import write_markdown
from experiments.paper.results import ConditionResult, Reproduction, SceneResult
from experiments.paper.scenes import PAPER_SCENES, Budget, SceneRecords, film_scene, frames_to_film
from experiments.paper.tracks import all_track_figures, per_region_object_figures

RESULTS_DIR = Path(__file__).resolve().parents[1] / "results"
FULL_BUDGET = Budget()
#: A few seconds of film per scene: enough for every output to exist, not for the numbers.
QUICK_BUDGET = Budget(preroll_s=45.0, warmup_s=1.0, scored_s=3.0)
#: Section 7's thresholds: contour area as a fraction of the frame.
BASELINE_FRACTIONS = (0.05, 0.005)
CONDITIONS = ("night", "day")
REPORT_NAME = "paper_comparison.md"
CONFUSION_PNG = "paper_confusion.png"
PR_PNG = "paper_precision_recall.png"


def cpu_name() -> str:
    """This machine's CPU model as the OS reports it."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown CPU"


def source_commit() -> str:
    """The checkout's short commit, flagged if detector/ or citysim/ differ from it."""
    root = Path(__file__).resolve().parents[2]

    def git(*args: str) -> str:
        done = subprocess.run(
            ["git", "-C", str(root), *args], capture_output=True, text=True, check=True
        )
        return done.stdout.strip()

    try:
        head = git("rev-parse", "--short", "HEAD")
        dirty = git("status", "--porcelain", "--untracked-files=no", "--", "detector", "citysim")
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return f"{head} with uncommitted changes to detector/ or citysim/" if dirty else head


def evaluate(
    name: str, keys: tuple[str, ...], per_scene: dict[str, SceneRecords]
) -> ConditionResult:
    """Pool the scenes ``keys`` and compute every figure of one condition."""
    pooled = SceneRecords()
    for key in keys:
        pooled.extend(per_scene[key])
    rows = {v: Rows.of(pooled, v) for v in VARIANTS}
    return ConditionResult(
        name=name,
        scenes=keys,
        records=pooled,
        confusions={v: confusions(rows[v]) for v in VARIANTS},
        precision_recall={v: precision_recall(rows[v]) for v in VARIANTS},
        baseline={f: threshold_baseline(pooled, f) for f in BASELINE_FRACTIONS},
        window=window_detection(pooled, n=5),
        by_distance=tpr_by_distance(pooled),
        tracks={"per frame": per_region_object_figures(pooled), **all_track_figures(pooled)},
    )


def reproduce(
    out_dir: Path,
    budget: Budget = FULL_BUDGET,
    scene_keys: tuple[str, ...] = tuple(PAPER_SCENES),
    *,
    quick: bool = False,
    progress: bool = True,
    full_frame: bool = False,
) -> Reproduction:
    """Film, score and report; returns everything written (see the module docstring).
    ``full_frame``: the detector segments whole frames (``film_scene``)."""
    unknown = [k for k in scene_keys if k not in PAPER_SCENES]
    if unknown:
        raise ValueError(f"scenes: unknown {unknown}; valid: {', '.join(PAPER_SCENES)}")
    scenes = [PAPER_SCENES[k] for k in scene_keys]
    missing = [c for c in CONDITIONS if not any(s.time_of_day == c for s in scenes)]
    if missing:
        raise ValueError(
            f"scenes: need at least one {' and one '.join(missing)} scene (the paper pools night and day)"
        )
    cv2.setNumThreads(1)  # the paper's detector is single-threaded; so is our timing
    total = sum(frames_to_film(s, budget) for s in scenes)
    per_scene: dict[str, SceneRecords] = {}
    with tqdm(total=total, unit="frame", desc="paper scenes", disable=not progress) as bar:
        for scene in scenes:
            bar.set_postfix_str(f"scene {scene.key}")
            per_scene[scene.key] = film_scene(scene, budget, on_frame=bar.update, full_frame=full_frame)
    scene_results = {}
    for s in scenes:
        cam = s.load().lamps.camera_model
        scene_results[s.key] = SceneResult(
            s.key, s.title, s.time_of_day, f"{cam.width_px}x{cam.height_px}", s.range_m,
            per_scene[s.key], confusions(Rows.of(per_scene[s.key], "objects")),
        )  # fmt: skip
    conditions = {
        c: evaluate(c, tuple(s.key for s in scenes if s.time_of_day == c), per_scene)
        for c in CONDITIONS
    }
    out_dir.mkdir(parents=True, exist_ok=True)
    night, day = conditions["night"], conditions["day"]
    files = {
        "confusion": plot_confusions(night.confusions["objects"], day.confusions["objects"], out_dir / CONFUSION_PNG),
        "precision_recall": plot_precision_recall(
            night.precision_recall["objects"], day.precision_recall["objects"], out_dir / PR_PNG,
            night.precision_recall["regions"], day.precision_recall["regions"],
        ),
    }  # fmt: skip
    result = Reproduction(
        scene_results, conditions, budget, quick, cpu_name(), files, source_commit()
    )
    files["report"] = write_markdown(result, out_dir / REPORT_NAME)
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m experiments.paper.reproduce", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--quick", action="store_true", help="a few seconds of film per scene (smoke test)"
    )
    parser.add_argument(
        "--out", type=Path, default=None, help="output folder (default experiments/results[/quick])"
    )
    parser.add_argument(
        "--scenes",
        nargs="+",
        default=list(PAPER_SCENES),
        metavar="KEY",
        help=f"paper scenes to film (default: all of {' '.join(PAPER_SCENES)})",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--full-frame", action="store_true",
                        help="segment whole frames, not the band where a target within range can appear")
    args = parser.parse_args(argv)
    out = args.out or (RESULTS_DIR / "quick" if args.quick else RESULTS_DIR)
    try:
        result = reproduce(out, QUICK_BUDGET if args.quick else FULL_BUDGET, tuple(args.scenes),
                           quick=args.quick, progress=not args.no_progress, full_frame=args.full_frame)  # fmt: skip
    except ValueError as exc:
        print(f"reproduce_paper: {exc}", file=sys.stderr)
        return 2
    night, day = result.conditions["night"], result.conditions["day"]
    n_obj, d_obj = night.confusions["objects"], day.confusions["objects"]
    print(f"night: FNR {1 - n_obj.tpr:.2f} (paper 0.24), FPR {n_obj.fpr:.2f} (paper 0.03); "
          f"day: TPR {d_obj.tpr:.2f} (paper 0.96), FPR {d_obj.fpr:.2f} (paper 0.05)")  # fmt: skip
    run, frames = night.tracks["run"], night.tracks["per frame"]
    print(f"night per object with tracks: miss {fmt(run.object_miss)} (per frame {fmt(frames.object_miss)}), "
          f"noise tracks called target {fmt(run.track_fpr)} (per frame {fmt(frames.track_fpr)}), "
          f"clean {fmt(run.clean_track_fpr)} (per frame {fmt(frames.clean_track_fpr)})")
    print(f"wrote {result.files['report']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
