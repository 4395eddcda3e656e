"""Command line: run the detector on a real video, or train a camera-specific model.

    python -m detector VIDEO --camera CAM.yaml --out DIR [--model M.joblib] [--max-width 424]
    python -m detector train --camera CAM.yaml --out MODEL.joblib [--seed 0]

Writes DIR/detections.csv (one row per classified region, noise included; boxes in the
video's own pixels; each with its track: id, class, pooled P(target), ground position and
speed), DIR/tracks.csv (one row per track: first and last frame, class, frames seen, mean
speed, why it was not a target), DIR/annotated.mp4 (the video at its own size with the boxes,
track ids and classes drawn; not with --no-video) and DIR/summary.json (counts, and the size the frames were
processed at). User errors print one
line naming the argument, file or field and exit with code 2; nothing half-written is left
behind, and an --out that cannot or should not be written is refused before any frame.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from pathlib import Path

import cv2
from tqdm import tqdm

from detector.camera import CameraError, CameraModel
from detector.classes import GENERAL_CAMERA_HEIGHT_M, GENERAL_MIN_VIEW_RANGE_M, GENERAL_TILT_DEG
from detector.cliargs import USAGE_EXIT, Parser, number
from detector.outdir import check_output_dir, check_output_file, exit_on_terminate, staged_output
from detector.video import (
    FrameScale,
    VideoError,
    camera_for_video,
    frame_scale,
    probe_video,
    source_and_gray_frames,
)

CSV_HEADER = ["frame", "x", "y", "w", "h", "cls", "p_target", "width_m", "height_m", "area_m2", "distance_m",
              "track_id", "track_cls", "track_p_target", "ground_x_m", "ground_y_m", "speed_mps"]
#: What an output folder of this command holds; an earlier one may be replaced by a new run.
DETECT_OUTPUTS = ("detections.csv", "tracks.csv", "annotated.mp4", "summary.json")
USER_ERRORS = (CameraError, VideoError, FileNotFoundError, ValueError)
MIN_MAX_WIDTH_PX = 64
#: Training a model for one camera takes about this long on one core of a small machine, s
#: (5 classes x DEFAULT_N_PER_CLASS synthetic silhouettes and a logistic regression).
CAMERA_TRAINING_S = 7
# the general model's cameras in words ("2-10 m high", "0-80 deg tilt")
_GENERAL_HEIGHTS = "{:g}-{:g} m high".format(*GENERAL_CAMERA_HEIGHT_M)
_GENERAL_TILTS = "{:g}-{:g} deg tilt".format(*GENERAL_TILT_DEG)


def detect_video(video: Path, camera_file: Path, out_dir: Path, model_path: Path | None = None,
                 max_width_px: int = 424, max_distance_m: float = 25.0, *, progress: bool = True,
                 annotated: bool = True, full_frame: bool = False) -> dict:
    """Run the detector over a video and write ``out_dir``; returns the summary (also in summary.json).

    Frames wider than ``max_width_px`` are processed scaled down; every box written or drawn
    is in the video's own pixels (``summary["processing"]`` states the scale). ``annotated``
    False writes no annotated.mp4: what a lamp's own small computer would do, and a third
    less time on the development clips (encoding the video at its own size costs more than
    detecting in it). ``full_frame``: segment whole frames, not only the band where a target
    within range can appear (``detector.roi``; for comparison, or a camera whose range covers
    the whole frame anyway).
    """
    from detector.detector import Detector

    if not max_width_px >= MIN_MAX_WIDTH_PX:
        raise ValueError(f"max_width_px: must be >= {MIN_MAX_WIDTH_PX} px, got {max_width_px}")
    if not max_distance_m > 0:
        raise ValueError(f"max_distance_m: must be > 0 m, got {max_distance_m}")
    check_output_dir(out_dir, "python -m detector", DETECT_OUTPUTS)
    camera = CameraModel.from_yaml(camera_file)
    info = probe_video(video)
    cam = camera_for_video(camera, info, max_width_px, camera_source=str(camera_file))
    scale = frame_scale(info, max_width_px)
    model, model_name = _choose_model(cam, camera_file, model_path)
    detector = Detector(cam, model=model, max_distance_m=max_distance_m, crop_to_range=not full_frame)
    detector.tracks.keep_ended = True  # for tracks.csv
    summary = {"video": str(video), "camera": str(camera_file), "model": model_name,
               "boxes": "x, y, w, h in the video's own pixels (OpenCV boundingRect: columns x .. x+w-1)",
               "processing": scale.as_dict(), "max_distance_m": max_distance_m, "fps": info.fps,
               "annotated_video": "annotated.mp4" if annotated else None, "full_frame": full_frame,
               # what was segmented, in the processed frame's pixels (half-open): the band, or everything
               "segmented_px": {"rows": [detector.crop.top_px, detector.crop.bottom_px],
                                "columns": [detector.crop.left_px, detector.crop.right_px]}}
    with staged_output(out_dir) as stage:
        counts = _detect_frames(detector, info, scale, stage, progress, annotated)
        counts["tracks"] = write_tracks_csv(detector.tracks, stage / "tracks.csv")
        summary.update(counts)
        (stage / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return {**summary, "processing_size_px": scale.processing_px, "video_size_px": scale.source_px,
            "out_dir": str(out_dir)}


def _choose_model(cam: CameraModel, camera_file: Path, model_path: Path | None):
    """The classifier for this camera and how to name it in the summary."""
    from detector.classifier import DimensionalClassifier
    from detector.general_model import default_model

    if model_path:
        return DimensionalClassifier.load(model_path), str(model_path)
    gap = general_model_gap(cam)
    if gap is None:
        return default_model(), "general"
    # a camera unlike those the general model was trained on: a model for this very camera is
    # a few seconds away and clearly better there
    print(f"note: {camera_file}: {gap}; training a model for this camera (~{CAMERA_TRAINING_S} s on an idle machine; "
          "save one with 'python -m detector train' to skip this)", file=sys.stderr)
    # the training code loads only here, for a camera the general model does not cover
    from detector.train.fit import train_camera_model

    return train_camera_model(cam), f"trained for {camera_file} (seed 0)"


def _detect_frames(detector, info, scale: FrameScale, stage: Path, progress: bool, annotated: bool) -> dict:
    """Detect in every frame: detections.csv and (``annotated``) annotated.mp4 at the video's size
    into ``stage``."""
    from detector.draw import draw_detections

    counts: dict[str, int] = {}
    frames_with_target = n_frames = 0
    writer = None
    if annotated:
        writer = cv2.VideoWriter(str(stage / "annotated.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), info.fps,
                                 scale.source_px)
        if not writer.isOpened():
            raise VideoError(f"{stage.parent}: OpenCV cannot write an mp4 video here")
    try:
        with open(stage / "detections.csv", "w", newline="") as fh:
            rows = csv.writer(fh)
            rows.writerow(CSV_HEADER)
            bar = tqdm(source_and_gray_frames(info, scale.processing_px), total=info.frame_count or None,
                       unit="frame", desc=f"detect {info.path.name}", disable=not progress)
            for n_frames, (source, gray) in enumerate(bar, start=1):
                detections = detector.process(gray)
                boxes = [scale.to_source_box(det.box_px) for det in detections]
                for det, (x, y, w, h) in zip(detections, boxes, strict=True):
                    wm, hm, am, dm = det.features[:4]
                    rows.writerow([n_frames - 1, x, y, w, h, det.cls, f"{det.p_target:.4f}",
                                   f"{wm:.3f}", f"{hm:.3f}", f"{am:.3f}", f"{dm:.3f}", det.track_id, det.track_cls,
                                   _fixed(det.track_p_target, 4), _fixed(det.ground_x_m, 3),
                                   _fixed(det.ground_y_m, 3), _fixed(det.speed_mps, 3)])
                    counts[det.cls] = counts.get(det.cls, 0) + 1
                frames_with_target += detector.is_target(detections)
                if writer is not None:
                    writer.write(draw_detections(source, detections, boxes_px=boxes))
    finally:
        if writer is not None:
            writer.release()
    return {"frames": n_frames, "frames_with_target": frames_with_target, "regions_per_class": counts}


def _fixed(value: float | None, digits: int) -> str:
    """A number with ``digits`` decimals, or an empty cell for None (not known yet)."""
    return "" if value is None else f"{value:.{digits}f}"


TRACKS_HEADER = ["track_id", "first_frame", "last_frame", "frames_seen", "cls", "target_frames", "mean_speed_mps",
                 "reject_reason", "merged_into"]


def write_tracks_csv(tracks, path: Path) -> dict[str, int]:
    """One row per track of the video (``detector.tracks``), by id; returns tracks per class.

    ``cls`` is the class the track had most often while it was a target, 'noise' if it never
    was one; ``reject_reason`` then says why (the reason of most of its frames);
    ``merged_into`` names the track it was joined to as a fragment.
    """
    counts: dict[str, int] = {}
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(TRACKS_HEADER)
        for t in sorted([*tracks.ended, *tracks.tracks], key=lambda t: t.track_id):
            cls = max(t.target_classes, key=t.target_classes.get) if t.target_classes else "noise"
            reason = "" if t.target_classes else max(t.reasons, key=t.reasons.get, default="")
            out.writerow([t.track_id, t.first_frame, t.last_frame, t.sightings, cls, t.target_frames,
                          _fixed(t.mean_speed_mps, 3), reason, "" if t.merged_into is None else t.merged_into])
            counts[cls] = counts.get(cls, 0) + 1
    return counts


def view_range_m(camera: CameraModel) -> float:
    """How far ahead the top image row meets the ground (inf when the horizon is in view), m."""
    top_depression_deg = camera.tilt_deg - camera.vertical_fov_deg / 2
    if top_depression_deg <= 0:
        return math.inf
    return camera.height_m / math.tan(math.radians(top_depression_deg))


def general_model_gap(camera: CameraModel) -> str | None:
    """Why the general model does not cover ``camera``, in words (None if it does): outside the
    ``detector.classes`` ``GENERAL_*`` ranges that its TrainingConfig defaults to."""
    reasons = []
    lo_h, hi_h = GENERAL_CAMERA_HEIGHT_M
    if not lo_h <= camera.height_m <= hi_h:
        reasons.append(f"camera {camera.height_m:g} m high: the general model covers {lo_h:g}-{hi_h:g} m")
    lo_t, hi_t = GENERAL_TILT_DEG
    if not lo_t <= camera.tilt_deg <= hi_t:
        reasons.append(f"camera tilted {camera.tilt_deg:g} deg below the horizon: the general model covers "
                       f"{lo_t:g}-{hi_t:g} deg")
    view_m = view_range_m(camera)
    if view_m < GENERAL_MIN_VIEW_RANGE_M:
        reasons.append(f"camera sees the ground only {view_m:.1f} m ahead: the general model's cameras see "
                       f"at least {GENERAL_MIN_VIEW_RANGE_M:g} m")
    return "; ".join(reasons) or None


def general_model_covers(camera: CameraModel) -> bool:
    """Is the camera like those the general model was trained on (``detector.classes``' ``GENERAL_*``
    ranges, which the general model's TrainingConfig defaults to)?"""
    return general_model_gap(camera) is None


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


USAGE = """python -m detector VIDEO --camera CAM.yaml --out DIR [options]
       python -m detector train [--camera CAM.yaml] --out MODEL.joblib [--seed N]"""


def _detect_parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m detector", usage=USAGE, description="Detect and classify moving objects in a "
               "video (pedestrian, group, cyclist, vehicle, noise). 'python -m detector train --help' trains "
               "a model for one camera.")
    p.add_argument("video", type=Path, help="video file (any format OpenCV decodes)")
    p.add_argument("--camera", type=Path, required=True, help="camera YAML: CameraModel fields (see scenarios/cameras/)")
    p.add_argument("--out", type=Path, required=True,
                   help="output folder for detections.csv, tracks.csv, annotated.mp4 and summary.json: new, empty, or an "
                        "earlier output of this command (replaced)")
    p.add_argument("--model", type=Path, default=None,
                   help="classifier .joblib (default: the general model, or one trained on the spot for a "
                        "camera outside its range)")
    p.add_argument("--max-width", type=number(int, ge=MIN_MAX_WIDTH_PX, unit="px"), default=424,
                   help="process frames scaled down to at most this width, px (boxes are written in the "
                        "video's own pixels)")
    p.add_argument("--max-distance-m", type=number(float, gt=0, unit="m"), default=25.0,
                   help="ignore objects farther than this, m")
    p.add_argument("--no-video", action="store_true",
                   help="write no annotated.mp4 (only the CSVs and summary.json, as a lamp's own computer would)")
    p.add_argument("--full-frame", action="store_true",
                   help="segment whole frames, not only the band where a target within --max-distance-m can appear")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def _train_parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m detector train", description="Train a classifier "
               "specialised to one camera, or without --camera the general model "
               "(the shipped detector/models/general.joblib is seed 0).")
    p.add_argument("--camera", type=Path, default=None,
                   help="camera YAML to specialise to (default: none, the general model)")
    p.add_argument("--out", type=Path, required=True, help="model file to write (.joblib)")
    p.add_argument("--seed", type=number(int, ge=0), default=0, help="random seed of the synthetic training set")
    return p


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    # killed from outside (SIGTERM), a job still removes its half-written output
    with exit_on_terminate():
        try:
            if argv and argv[0] == "train":
                return _train(_train_parser().parse_args(argv[1:]))
            args = _detect_parser().parse_args(argv)
            check_output_dir(args.out, "python -m detector", DETECT_OUTPUTS)  # detect_video checks again: an API
            summary = detect_video(args.video, args.camera, args.out, args.model, args.max_width,
                                   args.max_distance_m, progress=not args.no_progress, annotated=not args.no_video,
                                   full_frame=args.full_frame)
        except USER_ERRORS as exc:
            print(f"error: {exc}", file=sys.stderr)
            return USAGE_EXIT
    proc = summary["processing"]
    scaled = (f"processed at {proc['processing_width_px']}x{proc['processing_height_px']} px "
              f"(x{1 / proc['source_px_per_processing_px_x']:.3f}); boxes in the video's "
              f"{proc['video_width_px']}x{proc['video_height_px']} px")
    print(f"{summary['frames']} frames {scaled}; target in {summary['frames_with_target']} frames; "
          f"regions per class {summary['regions_per_class']}")
    print(f"tracks per class {summary['tracks']}")
    video = "" if args.no_video else " annotated.mp4,"
    print(f"results written to {args.out}/: detections.csv, tracks.csv,{video} summary.json")
    return 0


def _train(args: argparse.Namespace) -> int:
    from detector.train.sets import UnseenKindError

    check_output_file(args.out)
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


if __name__ == "__main__":
    sys.exit(main())
