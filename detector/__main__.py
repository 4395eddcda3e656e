"""Command line: run the detector on a real video, or train a camera-specific model.

    python -m detector VIDEO --camera CAM.yaml --out DIR [--model M.joblib] [--max-width 424]
    python -m detector train --camera CAM.yaml --out MODEL.joblib [--seed 0]

Writes DIR/detections.csv (one row per classified region, noise included) and
DIR/annotated.mp4. User errors print one line naming the file or field and exit
with code 2; nothing half-written is left behind.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from pathlib import Path

import cv2
from tqdm import tqdm

from detector.camera import CameraError, CameraModel
from detector.classes import GENERAL_CAMERA_HEIGHT_M, GENERAL_MIN_VIEW_RANGE_M, GENERAL_TILT_DEG
from detector.outdir import staged_output
from detector.video import VideoError, camera_for_video, gray_frames, probe_video

CSV_HEADER = ["frame", "x", "y", "w", "h", "cls", "p_target", "width_m", "height_m", "area_m2", "distance_m"]
USER_ERRORS = (CameraError, VideoError, FileNotFoundError, ValueError)
# the general model's cameras in words ("2-10 m high", "0-80 deg tilt")
_GENERAL_HEIGHTS = "{:g}-{:g} m high".format(*GENERAL_CAMERA_HEIGHT_M)
_GENERAL_TILTS = "{:g}-{:g} deg tilt".format(*GENERAL_TILT_DEG)


def detect_video(video: Path, camera_file: Path, out_dir: Path, model_path: Path | None = None,
                 max_width_px: int = 424, max_distance_m: float = 25.0, progress: bool = True) -> dict:
    """Run the detector over a video; returns a small summary dict (also printed by the CLI)."""
    from detector.classifier import DimensionalClassifier
    from detector.detector import Detector
    from detector.draw import draw_detections
    from detector.general_model import default_model

    camera = CameraModel.from_yaml(camera_file)
    info = probe_video(video)
    cam = camera_for_video(camera, info, max_width_px, camera_source=str(camera_file))
    if model_path:
        model = DimensionalClassifier.load(model_path)
    elif general_model_covers(cam):
        model = default_model()
    else:
        # a steep or low camera that never sees 25 m ahead lies outside what the general model was
        # trained on; a model for this very camera is a few seconds away and clearly better there
        print(f"note: {camera_file} sees only {view_range_m(cam):.1f} m ahead, outside the general model's "
              f"cameras ({_GENERAL_HEIGHTS}, seeing >= {GENERAL_MIN_VIEW_RANGE_M:g} m); training a model for this camera "
              f"(save one with 'python -m detector train' to skip this)", file=sys.stderr)
        # the training code loads only here, for a camera the general model does not cover
        from detector.train.fit import train_camera_model

        model = train_camera_model(cam)
    detector = Detector(cam, model=model, max_distance_m=max_distance_m)
    size = (cam.width_px, cam.height_px)
    counts: dict[str, int] = {}
    frames_with_target = 0
    n_frames = 0
    with staged_output(out_dir) as stage:
        writer = cv2.VideoWriter(str(stage / "annotated.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), info.fps, size)
        if not writer.isOpened():
            raise VideoError(f"{out_dir / 'annotated.mp4'}: OpenCV cannot write an mp4 video here")
        try:
            with open(stage / "detections.csv", "w", newline="") as fh:
                rows = csv.writer(fh)
                rows.writerow(CSV_HEADER)
                bar = tqdm(gray_frames(info, size), total=info.frame_count or None, unit="frame",
                           desc=f"detect {video.name}", disable=not progress)
                for n_frames, gray in enumerate(bar, start=1):
                    detections = detector.process(gray)
                    for det in detections:
                        x, y, w, h = det.box_px
                        wm, hm, am, dm = det.features[:4]
                        rows.writerow([n_frames - 1, x, y, w, h, det.cls, f"{det.p_target:.4f}",
                                       f"{wm:.3f}", f"{hm:.3f}", f"{am:.3f}", f"{dm:.3f}"])
                        counts[det.cls] = counts.get(det.cls, 0) + 1
                    frames_with_target += detector.is_target(detections)
                    writer.write(draw_detections(gray, detections))
        finally:
            writer.release()
    return {"frames": n_frames, "frames_with_target": frames_with_target, "regions_per_class": counts,
            "processing_size_px": size, "out_dir": str(out_dir)}


def view_range_m(camera: CameraModel) -> float:
    """How far ahead the top image row meets the ground (inf when the horizon is in view), m."""
    top_depression_deg = camera.tilt_deg - camera.vertical_fov_deg / 2
    if top_depression_deg <= 0:
        return math.inf
    return camera.height_m / math.tan(math.radians(top_depression_deg))


def general_model_covers(camera: CameraModel) -> bool:
    """Is the camera like those the general model was trained on (``detector.classes``' ``GENERAL_*``
    ranges, which the general model's TrainingConfig defaults to)?"""
    lo_h, hi_h = GENERAL_CAMERA_HEIGHT_M
    lo_t, hi_t = GENERAL_TILT_DEG
    return (lo_h <= camera.height_m <= hi_h and lo_t <= camera.tilt_deg <= hi_t
            and view_range_m(camera) >= GENERAL_MIN_VIEW_RANGE_M)


def train_camera(camera_file: Path | None, out_path: Path, seed: int = 0) -> Path:
    """Train a model and write it atomically to out_path: specialised to one camera, or
    (camera_file None) the general model over the Table 2 range of cameras, as shipped."""
    from detector.train.fit import DEFAULT_N_PER_CLASS, train_camera_model, train_general_model

    training = {"seed": seed, "n_per_class": DEFAULT_N_PER_CLASS}
    if camera_file is None:
        model = train_general_model(seed=seed)
        training["cameras"] = f"general (random cameras {_GENERAL_HEIGHTS}, {_GENERAL_TILTS})"
    else:
        camera = CameraModel.from_yaml(camera_file)
        model = train_camera_model(camera, seed=seed)
        training["cameras"] = str(camera_file)
    with staged_output(out_path.parent) as stage:
        model.save(stage / out_path.name, training=training)
    return out_path


def _detect_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m detector", description="Detect and classify moving objects in a video "
                                "(pedestrian, group, cyclist, vehicle, noise). Use 'python -m detector train' to "
                                "train a model for one camera.")
    p.add_argument("video", type=Path, help="video file (any format OpenCV decodes)")
    p.add_argument("--camera", type=Path, required=True, help="camera YAML (see scenarios/cameras/)")
    p.add_argument("--out", type=Path, required=True, help="output folder for detections.csv and annotated.mp4")
    p.add_argument("--model", type=Path, default=None, help="classifier .joblib (default: the general model)")
    p.add_argument("--max-width", type=int, default=424, help="process frames scaled to at most this width, px")
    p.add_argument("--max-distance-m", type=float, default=25.0, help="ignore objects farther than this, m")
    p.add_argument("--no-progress", action="store_true")
    return p


def _train_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m detector train", description="Train a classifier "
                                "specialised to one camera, or without --camera the general model "
                                "(the shipped detector/models/general.joblib is seed 0).")
    p.add_argument("--camera", type=Path, default=None,
                   help="camera YAML to specialise to (default: none, the general model)")
    p.add_argument("--out", type=Path, required=True, help="model file to write (.joblib)")
    p.add_argument("--seed", type=int, default=0)
    return p


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if argv and argv[0] == "train":
            args = _train_parser().parse_args(argv[1:])
            from detector.train.sets import UnseenKindError

            try:
                path = train_camera(args.camera, args.out, seed=args.seed)
            except UnseenKindError as exc:
                raise CameraError(
                    f"{args.camera}: this camera never sees a whole {exc.kind} in its frame "
                    f"({exc.seen} of {exc.attempts} tries), so no model can be trained for it; "
                    "check its height_m, tilt_deg and field of view"
                ) from None
            print(f"model written to {path}")
            return 0
        args = _detect_parser().parse_args(argv)
        if args.max_width < 64:
            raise ValueError(f"--max-width must be >= 64 px, got {args.max_width}")
        if args.max_distance_m <= 0:
            raise ValueError(f"--max-distance-m must be > 0, got {args.max_distance_m}")
        summary = detect_video(args.video, args.camera, args.out, args.model, args.max_width,
                               args.max_distance_m, progress=not args.no_progress)
    except USER_ERRORS as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"{summary['frames']} frames at {summary['processing_size_px'][0]}x{summary['processing_size_px'][1]} px; "
          f"target in {summary['frames_with_target']} frames; regions per class {summary['regions_per_class']}")
    print(f"results written to {args.out}/detections.csv and {args.out}/annotated.mp4")
    return 0


if __name__ == "__main__":
    sys.exit(main())
