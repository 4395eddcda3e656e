"""`citysim run | render | sweep | detect | plot`: the planner's command line.

Errors a user can cause print one line naming the file or field and what is
valid, and exit with code 2; nothing half-written is left behind.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

USAGE_EXIT = 2


def _user_errors() -> tuple[type[BaseException], ...]:
    from citysim.config.scenario import ScenarioError
    from citysim.sim.loop import RunError
    from detector.camera import CameraError
    from detector.video import VideoError

    errors = [ScenarioError, RunError, CameraError, VideoError]
    try:
        from citysim.sweep.runner import SweepError

        errors.append(SweepError)
    except ImportError:
        pass
    return tuple(errors)


def cmd_run(args) -> int:
    from citysim.config.scenario import load_scenario, override
    from citysim.sim.compare import default_workers, run_comparison

    scenario = load_scenario(args.scenario)
    updates = {}
    if args.duration is not None:
        updates["duration_s"] = args.duration
    if args.seed is not None:
        updates["seed"] = args.seed
    if updates:
        scenario = override(scenario, updates)
    names = [n.strip() for n in args.controllers.split(",") if n.strip()] if args.controllers else None
    workers = args.workers or default_workers()
    summary = run_comparison(scenario, names, progress=not args.no_progress, out_dir=args.out, workers=workers,
                             scenario_file=str(args.scenario))
    print(comparison_table(summary))
    print(f"\nresults written to {args.out}/: summary.json, objects.csv, lamps.csv, plots/")
    return 0


def comparison_table(summary: dict) -> str:
    """A plain-text table of the headline figures, one line per controller."""
    head = f"{'controller':<20} {'energy kWh':>10} {'savings':>8} {'lag p50 s':>9} {'lag p95 s':>9} {'lag max s':>9} " \
           f"{'dark s':>8} {'unlit':>6} {'switches':>8} {'false on s':>10}"
    lines = [f"{summary['scenario']}: {summary['duration_s']:.0f} s simulated, seed {summary['seed']}", head, "-" * len(head)]

    def num(v, fmt):
        return format(v, fmt) if v is not None else "-"

    for name, c in summary["controllers"].items():
        lines.append(f"{name:<20} {c['energy_kwh']:>10.3f} {c['savings_vs_always_on']:>8.1%} {num(c['lag_p50_s'], '9.2f')} "
                     f"{num(c['lag_p95_s'], '9.2f')} {num(c['lag_max_s'], '9.2f')} {c['dark_exposure_s']:>8.1f} "
                     f"{c['unlit_crossings']:>6d} {c['switches']:>8d} {c['false_on_time_s']:>10.0f}")
    return "\n".join(lines)


def cmd_render(args) -> int:
    from citysim.config.scenario import load_scenario
    from citysim.report.clip import render_clip

    scenario = load_scenario(args.scenario)
    stats = render_clip(scenario, args.lamp, args.duration, args.out, detect=args.detect, lamps_full=args.lamps_full,
                        progress=not args.no_progress)
    print(f"{stats['frames']} frames, {stats['truth_rows']} truth boxes"
          + (f", target detected in {stats['frames_with_target_detected']} frames" if args.detect else ""))
    print(f"results written to {args.out}/: camera.mp4, truth.csv, topdown.png")
    return 0


def cmd_sweep(args) -> int:
    from citysim.sweep.runner import run_sweep

    counts = run_sweep(args.sweep, args.out, scheduler=args.scheduler, workers=args.workers,
                       progress=not args.no_progress)
    print(f"{counts['points']} points: {counts['ran']} ran ({counts['ok']} ok, {counts['failed']} failed), "
          f"{counts['skipped']} already done")
    print(f"results written to {counts['results']}; plots and report: citysim plot {args.out}")
    return 0


def cmd_plot(args) -> int:
    from citysim.report import run_plots as plots
    from citysim.report.html import write_report

    folder = Path(args.dir)
    if (folder / "results.csv").exists():
        paths = plots.plot_sweep(folder)
    elif (folder / "summary.json").exists():
        paths = plots.plot_run(folder)
    else:
        from citysim.sim.loop import RunError

        raise RunError(f"{folder}: neither a run folder (summary.json) nor a sweep folder (results.csv)")
    report = write_report(folder)
    print(f"{len(paths)} plots written to {folder}/plots/; report: {report}")
    return 0


def cmd_detect(args) -> int:
    from detector.__main__ import main as detector_main

    argv = [str(args.video), "--camera", str(args.camera), "--out", str(args.out)]
    if args.model:
        argv += ["--model", str(args.model)]
    return detector_main(argv)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="citysim", description="Street-lighting scenarios with camera-driven lamps.")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="compare controllers on one scenario's night")
    r.add_argument("scenario", type=Path)
    r.add_argument("--out", type=Path, required=True)
    r.add_argument("--controllers", help="comma-separated names (default: the scenario's list)")
    r.add_argument("--duration", type=float, help="simulated seconds (default: the scenario's)")
    r.add_argument("--seed", type=int)
    r.add_argument("--workers", type=int, default=None, help="parallel processes (default: up to 2)")
    r.add_argument("--no-progress", action="store_true")
    r.set_defaults(func=cmd_run)

    rd = sub.add_parser("render", help="render one lamp camera's view with ground truth")
    rd.add_argument("scenario", type=Path)
    rd.add_argument("--lamp", type=int, default=0)
    rd.add_argument("--duration", type=float, default=20.0, help="simulated seconds")
    rd.add_argument("--out", type=Path, required=True)
    rd.add_argument("--detect", action="store_true", help="run the detector and draw its boxes")
    rd.add_argument("--lamps-full", action="store_true", help="render with every lamp at full level")
    rd.add_argument("--no-progress", action="store_true")
    rd.set_defaults(func=cmd_render)

    s = sub.add_parser("sweep", help="run a parameter sweep on Dask")
    s.add_argument("sweep", type=Path)
    s.add_argument("--out", type=Path, required=True)
    s.add_argument("--scheduler", help="Dask scheduler address (default: a local cluster)")
    s.add_argument("--workers", type=int, default=None)
    s.add_argument("--no-progress", action="store_true")
    s.set_defaults(func=cmd_sweep)

    d = sub.add_parser("detect", help="run the detector on a real video (same as python -m detector)")
    d.add_argument("video", type=Path)
    d.add_argument("--camera", type=Path, required=True)
    d.add_argument("--out", type=Path, required=True)
    d.add_argument("--model", type=Path)
    d.set_defaults(func=cmd_detect)


    pl = sub.add_parser("plot", help="plots and report.html for a run or sweep folder")
    pl.add_argument("dir", type=Path)
    pl.set_defaults(func=cmd_plot)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except _user_errors() as exc:
        print(f"error: {exc}", file=sys.stderr)
        return USAGE_EXIT


if __name__ == "__main__":
    sys.exit(main())
