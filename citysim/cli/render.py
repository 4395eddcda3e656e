"""`citysim render SCENARIO --out DIR`: one lamp camera's view of the night with its ground truth."""

from __future__ import annotations

from pathlib import Path

from citysim.cli.common import MAX_DURATION_S
from detector.cliargs import number
from detector.outdir import check_output_dir, staged_folder

#: What a render folder holds; an earlier one may be replaced.
RENDER_OUTPUTS = ("camera.mp4", "truth.csv", "topdown.png")


def cmd_render(args) -> int:
    from citysim.config.scenario import load_scenario
    from citysim.report.clip import render_clip

    scenario = load_scenario(args.scenario)
    check_output_dir(args.out, "citysim render", RENDER_OUTPUTS)
    with staged_folder(args.out) as stage:  # complete or absent: built aside, renamed into place
        stats = render_clip(scenario, args.lamp, args.duration, stage, start_s=args.start, detect=args.detect,
                            lamps_full=args.lamps_full, progress=not args.no_progress, camera_side=args.camera,
                            plain=args.plain)
    print(f"{stats['frames']} frames from t = {args.start:g} s, {stats['truth_rows']} truth boxes"
          + (f", target detected in {stats['frames_with_target_detected']} frames" if args.detect else ""))
    print(f"results written to {args.out}/: camera.mp4, truth.csv, topdown.png")
    return 0


def add(sub) -> None:
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
    rd.add_argument("--plain", action="store_true",
                    help="camera.mp4 without truth boxes or captions (the truth stays in truth.csv): footage "
                         "for python -m detector and its calibration")
    rd.add_argument("--no-progress", action="store_true", help="no progress bar")
    rd.set_defaults(func=cmd_render, out_lock=True)


