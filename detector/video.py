"""Reading a real video for the detector: open, validate, convert to grayscale, rescale.

A lamp's board processes small frames (the paper uses 320x240 to 424x240); a
larger video is scaled down to ``max_width_px`` and the camera's pixel grid with
it. The camera's intrinsics are in millimetres, so a new ``width_px`` /
``height_px`` rescales fx, fy and the principal point exactly. ``FrameScale``
maps the boxes found at the processing size back to the video's own pixels,
which is what a user sees and measures.
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
    if path.is_dir():
        raise VideoError(f"{path}: is a folder, not a video; valid: a video file (e.g. {path / 'clip.mp4'})")
    if not path.is_file():
        raise VideoError(f"{path}: video file not found")
    if path.stat().st_size == 0:
        raise VideoError(f"{path}: the file is empty (0 bytes); valid: a video file OpenCV can decode, e.g. .mp4 .avi")
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


@dataclass(frozen=True)
class FrameScale:
    """The video's size and the size the detector processes it at, px (width, height)."""

    source_px: tuple[int, int]
    processing_px: tuple[int, int]

    @property
    def factor_xy(self) -> tuple[float, float]:
        """Source pixels per processing pixel, along x and y (1.0 when not scaled)."""
        return self.source_px[0] / self.processing_px[0], self.source_px[1] / self.processing_px[1]

    def to_source_box(self, box_px: tuple[int, int, int, int]) -> tuple[int, int, int, int]:
        """A processing-size box (x, y, w, h; OpenCV boundingRect: columns x .. x+w-1) in source pixels.

        Pixel edges scale exactly (processing column i covers source edges i*f .. (i+1)*f); the
        scaled edges are rounded to the nearest source pixel edge, so the error is at most half
        a source pixel beyond what the processing resolution itself loses.
        """
        fx, fy = self.factor_xy
        x, y, w, h = box_px
        x0, y0 = round(x * fx), round(y * fy)
        x1, y1 = round((x + w) * fx), round((y + h) * fy)
        return x0, y0, max(1, x1 - x0), max(1, y1 - y0)

    def as_dict(self) -> dict:
        """For summary.json: sizes and factors, stated so a reader can convert either way."""
        fx, fy = self.factor_xy
        return {"video_width_px": self.source_px[0], "video_height_px": self.source_px[1],
                "processing_width_px": self.processing_px[0], "processing_height_px": self.processing_px[1],
                "source_px_per_processing_px_x": round(fx, 6), "source_px_per_processing_px_y": round(fy, 6)}


def frame_scale(info: VideoInfo, max_width_px: int) -> FrameScale:
    """How ``info``'s frames are scaled for processing at most ``max_width_px`` wide."""
    return FrameScale((info.width_px, info.height_px), processing_size(info.width_px, info.height_px, max_width_px))


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
    for _, gray in source_and_gray_frames(info, size_px):
        yield gray


def source_and_gray_frames(info: VideoInfo, size_px: tuple[int, int]) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield (the frame as decoded, uint8 grayscale at ``size_px`` (width, height)) pairs."""
    cap = cv2.VideoCapture(str(info.path))
    try:
        while True:
            ok, frame = cap.read()
            if not ok:
                return
            gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
            if (gray.shape[1], gray.shape[0]) != size_px:
                gray = cv2.resize(gray, size_px, interpolation=cv2.INTER_AREA)
            yield frame, gray
    finally:
        cap.release()
