"""Reading a real video for the detector: open, validate, convert to grayscale, rescale.

A lamp's board processes small frames (the paper uses 320x240 to 424x240); a
larger video is scaled down to ``max_width_px`` and the camera's pixel grid with
it. The camera's intrinsics are in millimetres, so a new ``width_px`` /
``height_px`` rescales fx, fy and the principal point exactly.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from detector.camera import CameraModel


class VideoError(ValueError):
    """A video that cannot be used; the message names the file and why."""


@dataclass(frozen=True)
class VideoInfo:
    path: Path
    width_px: int
    height_px: int
    fps: float
    frame_count: int  # as the container reports it; may be approximate


@contextmanager
def quiet_stderr() -> Iterator[None]:
    """Silence C libraries (FFmpeg) writing to fd 2, so a bad file gives our one message only."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def probe_video(path: str | Path) -> VideoInfo:
    """Open a video and decode its first frame; raise VideoError if that fails."""
    path = Path(path)
    if not path.is_file():
        raise VideoError(f"{path}: video file not found")
    with quiet_stderr():
        cap = cv2.VideoCapture(str(path))
    try:
        if not cap.isOpened():
            raise VideoError(f"{path}: cannot open as a video (valid: a file OpenCV's FFmpeg backend can decode, e.g. .mp4 .avi)")
        with quiet_stderr():
            ok, frame = cap.read()
        if not ok or frame is None:
            raise VideoError(f"{path}: no frame could be decoded (corrupt or empty video)")
        fps = cap.get(cv2.CAP_PROP_FPS) or 0.0
        count = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        return VideoInfo(path, frame.shape[1], frame.shape[0], fps if fps > 0 else 15.0, count)
    finally:
        cap.release()


def processing_size(width_px: int, height_px: int, max_width_px: int) -> tuple[int, int]:
    """The frame size the detector works at: at most max_width_px wide, same aspect ratio."""
    if width_px <= max_width_px:
        return width_px, height_px
    scale = max_width_px / width_px
    return max_width_px, max(16, round(height_px * scale))


def camera_for_video(camera: CameraModel, info: VideoInfo, max_width_px: int, camera_source: str = "camera") -> CameraModel:
    """The camera re-gridded to the processing size; its aspect ratio must match the video's."""
    cam_aspect = camera.width_px / camera.height_px
    vid_aspect = info.width_px / info.height_px
    if abs(cam_aspect - vid_aspect) > 0.02 * vid_aspect:
        raise VideoError(
            f"{camera_source}: width_px x height_px = {camera.width_px}x{camera.height_px} does not have the "
            f"aspect ratio of {info.path} ({info.width_px}x{info.height_px}); valid: a camera file for this video"
        )
    w, h = processing_size(info.width_px, info.height_px, max_width_px)
    return camera.placed(width_px=w, height_px=h, fps=info.fps)


def gray_frames(info: VideoInfo, size_px: tuple[int, int]) -> Iterator[np.ndarray]:
    """Yield uint8 grayscale frames at ``size_px`` (width, height)."""
    cap = cv2.VideoCapture(str(info.path))
    try:
        while True:
            ok, frame = cap.read()
            if not ok:
                return
            gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
            if (gray.shape[1], gray.shape[0]) != size_px:
                gray = cv2.resize(gray, size_px, interpolation=cv2.INTER_AREA)
            yield gray
    finally:
        cap.release()
