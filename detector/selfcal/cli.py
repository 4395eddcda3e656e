"""`python -m detector calibrate VIDEO (--focal-mm F --sensor-w-mm W | --hfov-deg H) --out camera.yaml`.

Estimates the camera's height and tilt from the people walking through the video
(``detector.selfcal.solve``), prints each with its uncertainty and the number of walkers it
rests on, and writes a camera file ``python -m detector`` reads. Roll is taken as 0 (not
estimated); the lens as distortion-free, with its principal point at the image centre.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from tqdm import tqdm

from detector.cliargs import USAGE_EXIT, Parser, number
from detector.outdir import check_output_file, staged_output
from detector.selfcal.solve import PRIOR_HEIGHT_M, CalibrationError, calibrate
from detector.selfcal.walkers import upright_tracks
from detector.video import VideoError, probe_video, processing_size, source_and_gray_frames

#: the focal length written when only the field of view is given, mm (any value gives the same camera)
NOMINAL_FOCAL_MM = 4.0
#: frames are processed at most this wide, px (as the detector does by default)
MAX_WIDTH_PX = 424


def calibrate_parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m detector calibrate",
               description="Estimate a camera's height and tilt from people walking through its video (the "
                           "lens must be known: focal length and sensor width, or the horizontal field of view) "
                           "and write a camera file for python -m detector.")
    p.add_argument("video", type=Path, help="video of the camera, with people walking towards or away from it")
    p.add_argument("--out", type=Path, required=True, help="camera YAML to write")
    p.add_argument("--focal-mm", type=number(float, gt=0, le=100, unit="mm"), default=None,
                   help="lens focal length, mm (with --sensor-w-mm)")
    p.add_argument("--sensor-w-mm", type=number(float, gt=0, le=100, unit="mm"), default=None,
                   help="sensor width, mm (with --focal-mm)")
    p.add_argument("--hfov-deg", type=number(float, gt=1, le=179, unit="deg"), default=None,
                   help="horizontal field of view, deg (instead of --focal-mm and --sensor-w-mm)")
    p.add_argument("--person-height-m", type=number(float, ge=1.0, le=2.2, unit="m"), default=PRIOR_HEIGHT_M,
                   help="mean height of the people walking by, m (Table 1's pedestrians: 1.15-2.0 m)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def _lens(args: argparse.Namespace) -> tuple[float, float]:
    """(focal mm, sensor width mm) from the arguments; ValueError naming them if not one of the two ways."""
    by_lens = args.focal_mm is not None or args.sensor_w_mm is not None
    if by_lens == (args.hfov_deg is not None):
        raise ValueError("--focal-mm/--sensor-w-mm/--hfov-deg: give either --focal-mm F --sensor-w-mm W (from "
                         "the lens datasheet) or --hfov-deg H (the horizontal field of view), not both or neither")
    if args.hfov_deg is not None:
        return NOMINAL_FOCAL_MM, 2 * NOMINAL_FOCAL_MM * math.tan(math.radians(args.hfov_deg) / 2)
    if args.focal_mm is None or args.sensor_w_mm is None:
        raise ValueError("--focal-mm/--sensor-w-mm: give both (or --hfov-deg alone)")
    return args.focal_mm, args.sensor_w_mm


def calibrate_main(argv: list[str]) -> int:
    """Run ``python -m detector calibrate``; user errors are one line and exit code 2."""
    args = calibrate_parser().parse_args(argv)
    try:
        focal_mm, sensor_w_mm = _lens(args)
        check_output_file(args.out)
        info = probe_video(args.video)
        w, h = processing_size(info.width_px, info.height_px, MAX_WIDTH_PX)
        frames = (gray for _, gray in tqdm(source_and_gray_frames(info, (w, h)), total=info.frame_count or None,
                                           unit="frame", desc=f"calibrate {info.path.name}",
                                           disable=args.no_progress))
        tracks = upright_tracks(frames, info.fps)
        sensor_h_mm = sensor_w_mm * info.height_px / info.width_px  # square pixels
        fx, fy = focal_mm * w / sensor_w_mm, focal_mm * h / sensor_h_mm
        cal = calibrate(tracks, w, h, fx, fy, info.fps, prior_height_m=args.person_height_m)
    except (CalibrationError, VideoError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return USAGE_EXIT
    camera = {"height_m": round(cal.height_m, 3), "tilt_deg": round(cal.tilt_deg, 2), "focal_mm": focal_mm,
              "sensor_w_mm": round(sensor_w_mm, 6), "sensor_h_mm": round(sensor_h_mm, 6),
              "width_px": info.width_px, "height_px": info.height_px, "fps": info.fps}
    lines = [f"# Estimated by python -m detector calibrate from {args.video} ({cal.walkers} walkers, "
             f"{cal.sightings} sightings; walkers' mean height taken as {cal.prior_height_m:g} m).",
             f"# height_m +- {cal.height_sd_m:.2f} m, tilt_deg +- {cal.tilt_sd_deg:.1f} deg (one standard deviation); "
             "roll taken as 0, no lens distortion.",
             f"name: {args.video.stem}_calibrated", *(f"{k}: {v}" for k, v in camera.items())]
    with staged_output(args.out.parent) as stage:
        (stage / args.out.name).write_text("\n".join(lines) + "\n")
    print(f"height {cal.height_m:.2f} +- {cal.height_sd_m:.2f} m, tilt {cal.tilt_deg:.1f} +- {cal.tilt_sd_deg:.1f} deg "
          f"below the horizon (roll taken as 0), from {cal.walkers} walkers ({cal.sightings} sightings)")
    if cal.walkers < 15:
        print(f"note: {cal.walkers} walkers is few; the height rests on their mean height: the more walkers, "
              "the nearer it comes (15 or more advised)", file=sys.stderr)
    print(f"camera written to {args.out}")
    return 0
