"""`citysim run | render | sweep | year | calibrate | validate | detect | plot`: the planner's command line.

`citysim year` lives in ``citysim.year_cli``.

Errors a user can cause print one line naming the argument, file or field and
what is valid, and exit with code 2; nothing half-written is left behind.
Every number and the --out folder are checked before any simulation starts.
"""

from __future__ import annotations

import argparse
import inspect
import sys
from pathlib import Path

from citysim.year_cli import add_year
from detector.cliargs import USAGE_EXIT, Parser, number
from detector.outdir import OutputDirError, check_output_dir, exit_on_terminate

#: What each command's output folder holds ("plots/" a folder); an earlier one may be replaced
#: (run, render) or resumed (sweep), a folder holding anything else is refused.
RUN_OUTPUTS = ("summary.json", "objects.csv", "lamps.csv", "plots/", "report.html")
RENDER_OUTPUTS = ("camera.mp4", "truth.csv", "topdown.png")
SWEEP_OUTPUTS = ("sweep.json", "results.csv", "results.csv.tmp", "points/", "plots/", "report.html")
#: The longest night a scenario may have (its duration_s limit), s.
MAX_DURATION_S = 7 * 86400


def _user_errors() -> tuple[type[BaseException], ...]:
    from citysim.config.scenario import ScenarioError
    from citysim.sim.loop import RunError
    from detector.camera import CameraError
    from detector.video import VideoError

    errors = [ScenarioError, RunError, CameraError, VideoError, OutputDirError]
    try:
        from citysim.sweep.runner import SweepError

        errors.append(SweepError)
    except ImportError:
        pass
    return tuple(errors)


def cmd_run(args) -> int:
    from citysim.config.scenario import load_scenario, override
    from citysim.sim.compare import controller_names, default_workers, run_comparison

    scenario = load_scenario(args.scenario)
    updates = {}
    if args.duration is not None:
        updates["duration_s"] = args.duration
    if args.seed is not None:
        updates["seed"] = args.seed
    if updates:
        scenario = override(scenario, updates)
    names = controller_names(args.controllers)
    check_output_dir(args.out, "citysim run", RUN_OUTPUTS)
    workers = args.workers or default_workers()
    summary = run_comparison(scenario, names, progress=not args.no_progress, out_dir=args.out, workers=workers,
                             scenario_file=str(args.scenario), fidelity=args.fidelity, cache_dir=args.cache)
    from citysim.report.run_plots import plot_run
    from citysim.report.table import comparison_table
    from citysim.report.topdown import plot_coverage_map
    from citysim.world.street import build_street

    # the run folder's data is written; its pictures are drawn here, outside the simulation (the
    # coverage map from the scenario's street, the rest from the run folder alone)
    plot_coverage_map(build_street(scenario), Path(args.out) / "plots" / "coverage.png")
    plot_run(args.out)
    print(comparison_table(summary))
    print("\n" + "\n".join(run_outputs(Path(args.out))))
    return 0


def run_outputs(out: Path) -> list[str]:
    """Write report.html beside the plots the run drew; the lines saying where everything is."""
    from citysim.report.html import write_report
    from citysim.report.run_plots import RUN_PLOTS

    plots = [out / "plots" / name for name in RUN_PLOTS if (out / "plots" / name).exists()]
    where = [("figures per controller", f"{out / 'summary.json'}"),
             ("per object and lamp", f"{out / 'objects.csv'}, {out / 'lamps.csv'}")]  # fmt: skip
    if plots:
        report = write_report(out, plots=plots)  # the plots run_comparison drew, not drawn again
        where += [(f"plots ({len(plots)} PNGs)", f"{out / 'plots'}/"),
                  ("report (open in a browser)", str(report))]  # fmt: skip
    width = max(len(label) for label, _ in where)
    return [f"results written to {out}/:"] + [f"  {label:<{width}}  {path}" for label, path in where]


def cmd_render(args) -> int:
    from citysim.config.scenario import load_scenario
    from citysim.report.clip import render_clip

    scenario = load_scenario(args.scenario)
    check_output_dir(args.out, "citysim render", RENDER_OUTPUTS)
    stats = render_clip(scenario, args.lamp, args.duration, args.out, start_s=args.start, detect=args.detect,
                        lamps_full=args.lamps_full, progress=not args.no_progress, camera_side=args.camera)
    print(f"{stats['frames']} frames from t = {args.start:g} s, {stats['truth_rows']} truth boxes"
          + (f", target detected in {stats['frames_with_target_detected']} frames" if args.detect else ""))
    print(f"results written to {args.out}/: camera.mp4, truth.csv, topdown.png")
    return 0


def cmd_sweep(args) -> int:
    from citysim.sim.validation import TOLERANCE_NOTE
    from citysim.sweep.runner import run_sweep

    check_output_dir(args.out, "citysim sweep", SWEEP_OUTPUTS)  # an earlier folder of this sweep resumes
    counts = run_sweep(args.sweep, args.out, scheduler=args.scheduler, workers=args.workers,
                       progress=not args.no_progress, fidelity=args.fidelity, full_checks=args.full_checks,
                       cache_dir=args.cache)  # fmt: skip
    print(f"{counts['points']} points ({args.fidelity} fidelity): {counts['ran']} ran ({counts['ok']} ok, "
          f"{counts['failed']} failed), {counts['skipped']} already done")
    if "check" in counts:
        check = counts["check"]
        print(f"full-fidelity check of {check['points']} points: {check['cells_pass']} of {check['cells']} figures "
              f"agree ({TOLERANCE_NOTE}); {check['file']}")
    print(f"results written to {counts['results']}; plots and report: citysim plot {args.out}")
    return 0


def cmd_calibrate(args) -> int:
    from citysim.config.scenario import load_scenario
    from citysim.sim.calibration import calibrate

    scenario = load_scenario(args.scenario)
    model, path = calibrate(scenario, args.cache, duration_s=args.duration, runs=args.runs,
                            progress=not args.no_progress, workers=args.workers)  # fmt: skip
    print(f"sensor model of {scenario.name}: fitted on {model.frames} judged camera frames, "
          f"{model.candidate_frames} candidate sightings; false alarms started "
          f"{model.fa_per_camera_hour:.1f} per camera-hour")
    print(f"results written to {path}")
    return 0


def cmd_validate(args) -> int:
    from citysim.config.scenario import load_scenario
    from citysim.sim.compare import controller_names, resolve_controllers
    from citysim.sim.validation import validate, validation_table

    scenario = load_scenario(args.scenario)
    names = controller_names(args.controllers)
    if names:
        resolve_controllers(scenario, names)  # unknown names fail here, before any work
    result = validate(scenario, seeds=args.seeds, duration_s=args.duration, controllers=names, cache_dir=args.cache,
                      workers=args.workers, progress=not args.no_progress)  # fmt: skip
    print(validation_table(result))
    return 0


def cmd_plot(args) -> int:
    from citysim.report.html import write_report
    from citysim.report.run_plots import plot_run
    from citysim.report.sweep_plots import plot_sweep

    folder = Path(args.dir)
    if (folder / "results.csv").exists():
        paths = plot_sweep(folder)
    elif (folder / "summary.json").exists():
        paths = plot_run(folder)
    else:
        from citysim.sim.loop import RunError

        raise RunError(f"{folder}: neither a run folder (summary.json) nor a sweep folder (results.csv)")
    report = write_report(folder, plots=paths)  # the plots just drawn: not drawn twice
    print(f"{len(paths)} plots written to {folder}/plots/; report: {report}")
    return 0


def cmd_detect(args) -> int:
    from detector.__main__ import main as detector_main

    argv = [str(args.video), "--camera", str(args.camera), "--out", str(args.out), "--max-width", str(args.max_width),
            "--max-distance-m", str(args.max_distance_m)]
    if args.no_progress:
        argv.append("--no-progress")
    if args.model:
        argv += ["--model", str(args.model)]
    return detector_main(argv)


def controller_list() -> str:
    """The registered controllers, one line each (for ``citysim run --help``)."""
    from citysim.control.registry import CONTROLLERS

    lines = ["controllers (--controllers, or the scenario's `controllers` list):"]
    for name, cls in CONTROLLERS.items():
        doc = (inspect.getdoc(cls) or "").splitlines()[0]
        fraction = getattr(cls, "fraction", None)
        if fraction is not None:  # the threshold baselines differ only in it
            doc = f"{doc.rstrip('.')}: {fraction:.1%}"
        lines.append(f"  {name:<19} {doc}")
    return "\n".join(lines)


def _add_run(sub) -> None:
    r = sub.add_parser("run", help="compare controllers on one scenario's night", epilog_fn=controller_list,
                       description="Simulate the scenario's night once per controller, on the same traffic, and "
                                   "write a run folder: summary.json, objects.csv, lamps.csv, plots/.")
    r.add_argument("scenario", type=Path, help="scenario YAML file (see scenarios/suburban_night.yaml)")
    r.add_argument("--out", type=Path, required=True,
                   help="run folder to write: new, empty, or an earlier run folder (replaced)")
    r.add_argument("--controllers", help="comma-separated controller names, listed below; always_on is added "
                                         "for the savings (default: the scenario's list)")
    r.add_argument("--duration", type=number(float, gt=0, le=MAX_DURATION_S, unit="s"),
                   help="simulated seconds (default: the scenario's duration_s)")
    r.add_argument("--seed", type=number(int, ge=0),
                   help="random seed of the traffic, scenery and sensor noise (default: the scenario's seed)")
    r.add_argument("--workers", type=number(int, ge=1), default=None,
                   help="parallel processes, one controller each (default: 2, or 1 on a one-core machine)")
    _add_fidelity(r, "full")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_run)


def _add_fidelity(parser, default: str) -> None:
    from citysim.fast import FIDELITIES

    parser.add_argument("--fidelity", choices=FIDELITIES, default=default,
                        help=f"full: render every judged camera frame for the real detector; fast: a sensor model "
                             f"calibrated on full-fidelity frames of this scenario's cameras (calibrated on first use; "
                             f"see citysim calibrate). Default: {default}")  # fmt: skip
    _add_cache(parser)


def _add_cache(parser) -> None:
    parser.add_argument("--cache", type=Path, default=None,
                        help="folder of calibrated sensor models (default: .cache/sensor_models in the project)")


def _add_calibrate_validate(sub) -> None:
    c = sub.add_parser("calibrate", help="fit a scenario's fast-mode sensor model",
                       description="Render and detect the scenario's cameras in full fidelity on calibration seeds "
                                   "(never used for validation), busy nights and quiet nights with every lamp dim, "
                                   "fit the sensor model fast mode draws from, and "
                                   "cache it by a hash of the cameras, street, environment, traffic kinds and "
                                   "detector model.")
    c.add_argument("scenario", type=Path, help="scenario YAML file")
    _add_cache(c)
    c.add_argument("--duration", type=number(float, gt=0, le=MAX_DURATION_S, unit="s"), default=120.0,
                   help="simulated seconds per calibration night")
    c.add_argument("--runs", type=number(int, ge=1), default=2,
                   help="calibration nights of each kind: busy (the lamps switched as usual) and quiet (every "
                        "lamp held dim), each on a seed of its own")
    c.add_argument("--workers", type=number(int, ge=1), default=2, help="parallel processes, one night each")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    c.set_defaults(func=cmd_calibrate)

    v = sub.add_parser("validate", help="compare fast mode against full fidelity, per controller",
                       description="Run the scenario's controllers in full fidelity and in fast mode on the "
                                   "scenario's seed and the next ones (never calibration seeds) and print "
                                   "savings, lit on entry, lag p95 and false on-time side by side, each marked "
                                   "PASS or MISS against its tolerance.")
    v.add_argument("scenario", type=Path, help="scenario YAML file")
    v.add_argument("--duration", type=number(float, gt=0, le=MAX_DURATION_S, unit="s"), default=120.0,
                   help="simulated seconds per seed (longer: steadier figures, minutes more)")
    v.add_argument("--seeds", type=number(int, ge=1), default=2, help="validation seeds")
    v.add_argument("--controllers", help="comma-separated controller names (default: the scenario's list)")
    v.add_argument("--workers", type=number(int, ge=1), default=2, help="parallel processes for the full runs")
    _add_cache(v)
    v.add_argument("--no-progress", action="store_true", help="no progress bar")
    v.set_defaults(func=cmd_validate)


def _add_render(sub) -> None:
    rd = sub.add_parser("render", help="render one lamp camera's view with ground truth",
                        description="Render one lamp camera's view of the scenario's night: camera.mp4 (truth "
                                    "boxes; with --detect the detector's boxes in a second half beside them), "
                                    "truth.csv and topdown.png.")
    rd.add_argument("scenario", type=Path, help="scenario YAML file")
    rd.add_argument("--lamp", type=number(int, ge=0), default=0, help="lamp index, 0 .. the scenario's lamps - 1")
    rd.add_argument("--camera", choices=("forward", "backward"), default="forward",
                    help="which of the pole's cameras: its own (forward) or the backward one "
                         "(scenarios with lamps.camera.back_heading_deg)")
    rd.add_argument("--start", type=number(float, ge=0, unit="s"), default=0.0,
                    help="seconds into the night the clip starts (within the scenario's duration_s)")
    rd.add_argument("--duration", type=number(float, gt=0, le=MAX_DURATION_S, unit="s"), default=20.0,
                    help="clip length, simulated seconds")
    rd.add_argument("--out", type=Path, required=True,
                    help="folder to write: new, empty, or an earlier render folder (replaced)")
    rd.add_argument("--detect", action="store_true", help="run the detector and show its boxes beside the truth")
    rd.add_argument("--lamps-full", action="store_true", help="render with every lamp at full level "
                                                                "(default: at the luminaire's dim_level)")
    rd.add_argument("--no-progress", action="store_true", help="no progress bar")
    rd.set_defaults(func=cmd_render)


def build_parser() -> argparse.ArgumentParser:
    p = Parser(prog="citysim", description="Street-lighting scenarios with camera-driven lamps. "
                                           "'citysim COMMAND --help' describes each command.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser, metavar="COMMAND")
    _add_run(sub)
    _add_render(sub)
    add_year(sub, epilog_fn=controller_list)

    s = sub.add_parser("sweep", help="run a parameter sweep on Dask",
                       description="Run every point of a sweep file; a folder of the same sweep resumes.")
    s.add_argument("sweep", type=Path, help="sweep YAML file (see experiments/sweeps/)")
    s.add_argument("--out", type=Path, required=True,
                   help="sweep folder: new, empty, or an earlier folder of this sweep (resumed)")
    s.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://HOST:8786 (default: a local cluster)")
    s.add_argument("--workers", type=number(int, ge=1), default=None,
                   help="local cluster processes (default: one per CPU)")
    _add_fidelity(s, "fast")
    s.add_argument("--full-checks", type=number(int, ge=0), default=2,
                   help="in fast mode, this many points (evenly spread) are re-run in full fidelity and compared")
    s.add_argument("--no-progress", action="store_true", help="no progress bar")
    s.set_defaults(func=cmd_sweep)
    _add_calibrate_validate(sub)

    d = sub.add_parser("detect", help="run the detector on a real video (same as python -m detector)",
                       description="Run the detector on a real video (same as python -m detector).")
    d.add_argument("video", type=Path, help="video file (any format OpenCV decodes)")
    d.add_argument("--camera", type=Path, required=True, help="camera YAML (see scenarios/cameras/)")
    d.add_argument("--out", type=Path, required=True,
                   help="folder for detections.csv, annotated.mp4, summary.json: new, empty, or an earlier one")
    d.add_argument("--model", type=Path, help="classifier .joblib (default: the general model)")
    d.add_argument("--max-width", type=number(int, ge=64, unit="px"), default=424,
                   help="process frames scaled down to at most this width, px (boxes stay in the video's pixels)")
    d.add_argument("--max-distance-m", type=number(float, gt=0, unit="m"), default=25.0,
                   help="ignore objects farther than this, m")
    d.add_argument("--no-progress", action="store_true", help="no progress bar")
    d.set_defaults(func=cmd_detect)

    pl = sub.add_parser("plot", help="plots and report.html for a run or sweep folder",
                        description="Draw the plots and report.html of a run or sweep folder.")
    pl.add_argument("dir", type=Path, help="a run folder (summary.json) or sweep folder (results.csv)")
    pl.set_defaults(func=cmd_plot)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    # killed from outside (SIGTERM), a job still removes its half-written output
    with exit_on_terminate():
        try:
            return args.func(args)
        except _user_errors() as exc:
            print(f"error: {exc}", file=sys.stderr)
            return USAGE_EXIT


if __name__ == "__main__":
    sys.exit(main())
