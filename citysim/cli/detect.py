"""`citysim detect VIDEO --camera CAMERA --out DIR`: the detector on a real video (as `python -m detector`)."""

from __future__ import annotations

from pathlib import Path

from detector.cliargs import number


def cmd_detect(args) -> int:
    from detector.__main__ import main as detector_main

    argv = [str(args.video), "--camera", str(args.camera), "--out", str(args.out), "--max-width", str(args.max_width),
            "--max-distance-m", str(args.max_distance_m)]
    if args.no_progress:
        argv.append("--no-progress")
    if args.model:
        argv += ["--model", str(args.model)]
    return detector_main(argv)


def add(sub) -> None:
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

