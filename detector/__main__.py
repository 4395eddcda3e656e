"""Command line: run the detector on a video, calibrate a camera from its passers-by, or train a model.

    python -m detector VIDEO --camera CAM.yaml --out DIR [--model M.joblib] [--max-width 424]
    python -m detector calibrate VIDEO (--focal-mm F --sensor-w-mm W | --hfov-deg H) --out CAM.yaml
    python -m detector train --camera CAM.yaml --out MODEL.joblib [--seed 0]

Writes DIR/detections.csv (one row per classified region, noise included; boxes in the
video's own pixels; ``target`` 1/0 is what a lamp would act on, the track's decision where
there is a track; ``frame_cls``/``frame_p_target`` are the per-frame classifier's output;
``detector.detections_csv``), DIR/tracks.csv (one row per track: first and last frame, class,
frames seen, mean speed, why it was not a target), DIR/annotated.mp4 (the video at its own size
with each region's decision drawn; not with --no-video) and DIR/summary.json (counts of the
CSV's rows, and the size the frames were processed at). A model trained for a camera outside
the general model's range is cached (``detector.model_cache``). User errors print one line
naming the argument, file or field and exit with code 2; Ctrl-C prints one line and exits 130
(SIGTERM: 143); nothing half-written is left behind, and an --out that cannot or should not be
written is refused before any frame.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import cv2
from tqdm import tqdm

from detector.camera import CameraError, CameraModel
from detector.classes import GENERAL_CAMERA_HEIGHT_M, GENERAL_MIN_VIEW_RANGE_M, GENERAL_TILT_DEG
from detector.cliargs import USAGE_EXIT, Parser, number
from detector.detections_csv import CSV_HEADER, DetectionRows, write_tracks_csv
from detector.outdir import (
    TERMINATED_EXIT,
    check_output_dir,
    check_output_file,
    exit_on_terminate,
    staged_output,
)
from detector.video import (
    FrameScale,
    VideoError,
    camera_for_video,
    frame_scale,
    probe_video,
    source_and_gray_frames,
)

__all__ = ["CSV_HEADER", "add_detect_arguments", "detect_video", "main", "run_detect", "write_tracks_csv"]
#: What an output folder of this command holds; an earlier one may be replaced by a new run.
DETECT_OUTPUTS = ("detections.csv", "tracks.csv", "annotated.mp4", "summary.json")
USER_ERRORS = (CameraError, VideoError, FileNotFoundError, ValueError)
MIN_MAX_WIDTH_PX = 64
#: exit status after Ctrl-C (128 + SIGINT), as shells report it
INTERRUPTED_EXIT = 130
#: Training a model for one camera takes about this long on one core of a small machine, s
#: (5 classes x DEFAULT_N_PER_CLASS synthetic silhouettes and a logistic regression).
CAMERA_TRAINING_S = 7
# the general model's cameras in words ("2-10 m high", "0-80 deg tilt")
_GENERAL_HEIGHTS = "{:g}-{:g} m high".format(*GENERAL_CAMERA_HEIGHT_M)
_GENERAL_TILTS = "{:g}-{:g} deg tilt".format(*GENERAL_TILT_DEG)


def detect_video(video: Path, camera_file: Path, out_dir: Path, model_path: Path | None = None,
                 max_width_px: int = 424, max_distance_m: float = 25.0, *, progress: bool = True,
                 annotated: bool = True, full_frame: bool = False, border_filter: bool = True) -> dict:
    """Run the detector over a video and write ``out_dir``; returns the summary (also in summary.json).

    Frames wider than ``max_width_px`` are processed scaled down; every box written or drawn
    is in the video's own pixels (``summary["processing"]`` states the scale). ``annotated``
    False writes no annotated.mp4: what a lamp's own small computer would do, and a third
    less time on the development clips (encoding the video at its own size costs more than
    detecting in it). ``full_frame``: segment whole frames, not only the band where a target
    within range can appear (``detector.roi``; for comparison, or a camera whose range covers
    the whole frame anyway). ``border_filter``: drop every region cut by the frame's edge, as
    the paper does (the default); False: keep those that continue a track or, cut by the left,
    right or top edge, fit a class on their own (``detector.edges``), measured from their visible part.
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
    detector = Detector(cam, model=model, max_distance_m=max_distance_m, crop_to_range=not full_frame,
                        border_filter=border_filter)
    detector.tracks.keep_ended = True  # for tracks.csv
    summary = {"video": str(video), "camera": str(camera_file), "model": model_name,
               "boxes": "x, y, w, h in the video's own pixels (OpenCV boundingRect: columns x .. x+w-1)",
               "answer": "detections.csv's target column (1: a lamp acts on it; the track's decision where "
                         "there is a track); frame_cls is the per-frame classifier's output, not the answer",
               "processing": scale.as_dict(), "max_distance_m": max_distance_m, "fps": info.fps,
               "annotated_video": "annotated.mp4" if annotated else None, "full_frame": full_frame,
               "border_filter": border_filter,
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
    # a few seconds away (once: it is cached) and clearly better there
    from detector.model_cache import cached_camera_model
    from detector.train.fit import DEFAULT_N_PER_CLASS, train_camera_model

    def train(camera: CameraModel):
        print(f"note: {camera_file}: {gap}; training a model for this camera (~{CAMERA_TRAINING_S} s on an idle "
              "machine, once: it is cached)", file=sys.stderr)
        return train_camera_model(camera)

    model, path, reused = cached_camera_model(cam, train, seed=0, n_per_class=DEFAULT_N_PER_CLASS)
    if reused:
        print(f"note: {camera_file}: {gap}; reusing the model trained for this camera: {path}", file=sys.stderr)
    return model, f"trained for {camera_file} (seed 0; cached as {path})"


def _detect_frames(detector, info, scale: FrameScale, stage: Path, progress: bool, annotated: bool) -> dict:
    """Detect in every frame: detections.csv and (``annotated``) annotated.mp4 at the video's size
    into ``stage``; returns the counts of detections.csv's rows."""
    from detector.draw import draw_detections

    n_frames = 0
    writer = None
    if annotated:
        writer = cv2.VideoWriter(str(stage / "annotated.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), info.fps,
                                 scale.source_px)
        if not writer.isOpened():
            raise VideoError(f"{stage.parent}: OpenCV cannot write an mp4 video here")
    try:
        with open(stage / "detections.csv", "w", newline="") as fh:
            rows = DetectionRows(fh, detector.target_threshold)
            bar = tqdm(source_and_gray_frames(info, scale.processing_px), total=info.frame_count or None,
                       unit="frame", desc=f"detect {info.path.name}", disable=not progress)
            for n_frames, (source, gray) in enumerate(bar, start=1):
                detections = detector.process(gray)
                boxes = [scale.to_source_box(det.box_px) for det in detections]
                rows.write_frame(n_frames - 1, detections, boxes)
                if writer is not None:
                    writer.write(draw_detections(source, detections, boxes_px=boxes,
                                                 target_threshold=detector.target_threshold))
    finally:
        if writer is not None:
            writer.release()
    return {"frames": n_frames, **rows.counts()}


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
       python -m detector calibrate VIDEO (--focal-mm F --sensor-w-mm W | --hfov-deg H) --out CAM.yaml
       python -m detector train [--camera CAM.yaml] --out MODEL.joblib [--seed N]"""
#: what to do without a camera file
HOW_TO_GET_A_CAMERA = ("a camera file (height_m, tilt_deg, lens) is needed to measure objects; let the detector "
                       "estimate one from people walking by: 'python -m detector calibrate VIDEO --hfov-deg H "
                       "--out camera.yaml' (or --focal-mm F --sensor-w-mm W from the lens datasheet), or write one "
                       "by hand (see scenarios/cameras/)")


def add_detect_arguments(p: argparse.ArgumentParser) -> None:
    """Every option of ``python -m detector VIDEO``, on ``p``: the one definition both that
    command and ``citysim detect`` use (``run_detect`` runs the parsed arguments)."""
    p.add_argument("video", type=Path, help="video file (any format OpenCV decodes)")
    p.add_argument("--camera", type=Path, default=None,
                   help="camera YAML: CameraModel fields (see scenarios/cameras/); none yet? "
                        "'python -m detector calibrate' estimates one from the video")
    p.add_argument("--out", type=Path, required=True,
                   help="output folder for detections.csv, tracks.csv, annotated.mp4 and summary.json: new, empty, or an "
                        "earlier output of this command (replaced)")
    p.add_argument("--model", type=Path, default=None,
                   help="classifier .joblib (default: the general model, or one trained for a camera outside its "
                        "range, cached after the first run)")
    p.add_argument("--max-width", type=number(int, ge=MIN_MAX_WIDTH_PX, unit="px"), default=424,
                   help="process frames scaled down to at most this width, px (boxes are written in the "
                        "video's own pixels)")
    p.add_argument("--max-distance-m", type=number(float, gt=0, unit="m"), default=25.0,
                   help="ignore objects farther than this, m")
    p.add_argument("--no-video", action="store_true",
                   help="write no annotated.mp4 (only the CSVs and summary.json, as a lamp's own computer would)")
    p.add_argument("--full-frame", action="store_true",
                   help="segment whole frames, not only the band where a target within --max-distance-m can appear")
    p.add_argument("--keep-edge-regions", action="store_true",
                   help="keep a region cut by the frame's edge, measured from its visible part, when it "
                        "continues a track or (cut by the left, right or top edge) its visible part fits a class; "
                        "default: drop every region cut by the edge, as the paper does")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _detect_parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m detector", usage=USAGE, description="Detect and classify moving objects in a "
               "video (pedestrian, group, cyclist, vehicle, noise). 'python -m detector calibrate --help' "
               "estimates the camera file from people walking by; 'python -m detector train --help' trains "
               "a model for one camera.")
    add_detect_arguments(p)
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


def run_detect(args: argparse.Namespace) -> int:
    """Run parsed ``add_detect_arguments`` arguments: detect, print what was found and where it was
    written; a user error is one line and exit code 2."""
    try:
        if args.camera is None:
            print(f"error: --camera: {HOW_TO_GET_A_CAMERA}", file=sys.stderr)
            return USAGE_EXIT
        check_output_dir(args.out, "python -m detector", DETECT_OUTPUTS)  # detect_video checks again: an API
        summary = detect_video(args.video, args.camera, args.out, args.model, args.max_width,
                               args.max_distance_m, progress=not args.no_progress, annotated=not args.no_video,
                               full_frame=args.full_frame, border_filter=not args.keep_edge_regions)
    except USER_ERRORS as exc:
        print(f"error: {exc}", file=sys.stderr)
        return USAGE_EXIT
    proc = summary["processing"]
    scaled = (f"processed at {proc['processing_width_px']}x{proc['processing_height_px']} px "
              f"(x{1 / proc['source_px_per_processing_px_x']:.3f}); boxes in the video's "
              f"{proc['video_width_px']}x{proc['video_height_px']} px")
    print(f"{summary['frames']} frames {scaled}; target in {summary['frames_with_target']} frames "
          f"(detections.csv's target column); target rows per class {summary['target_rows_per_class']}")
    print(f"tracks per class {summary['tracks']}")
    video = "" if args.no_video else " annotated.mp4,"
    print(f"results written to {args.out}/: detections.csv, tracks.csv,{video} summary.json")
    return 0


def interruptible(job, out: str | Path | None) -> int:
    """``job()``'s exit code; Ctrl-C (or SIGTERM, within ``exit_on_terminate``) ends it with one
    line, 'interrupted: ...', and exit 130 (143), no traceback. ``out``: what the job writes;
    its staged output is already gone when the line is printed (``detector.outdir``)."""
    where = "nothing written" if out is None else f"{out} left as it was"
    try:
        return job()
    except KeyboardInterrupt:
        code = INTERRUPTED_EXIT
    except SystemExit as exc:
        if exc.code != TERMINATED_EXIT:
            raise
        code = TERMINATED_EXIT
    sys.stderr.write(f"\ninterrupted: {where}\n")
    return code


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    # killed from outside (SIGTERM), a job still removes its half-written output
    with exit_on_terminate():
        if argv and argv[0] == "train":
            args = _train_parser().parse_args(argv[1:])
            return interruptible(lambda: _train(args), args.out)
        if argv and argv[0] == "calibrate":
            from detector.selfcal.cli import calibrate_main

            return interruptible(lambda: calibrate_main(argv[1:]), None)
        args = _detect_parser().parse_args(argv)
        return interruptible(lambda: run_detect(args), args.out)


def _train(args: argparse.Namespace) -> int:
    from detector.train.sets import UnseenKindError

    try:
        check_output_file(args.out)
        try:
            path = train_camera(args.camera, args.out, seed=args.seed)
        except UnseenKindError as exc:
            raise CameraError(
                f"{args.camera}: this camera never sees a whole {exc.kind} in its frame "
                f"({exc.seen} of {exc.attempts} tries), so no model can be trained for it; "
                "check its height_m, tilt_deg and field of view"
            ) from None
    except USER_ERRORS as exc:
        print(f"error: {exc}", file=sys.stderr)
        return USAGE_EXIT
    print(f"model written to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
