"""Drawing detections on a frame (for annotated videos; never used in the detection path)."""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

#: BGR colour per class; noise is drawn thin and grey so targets stand out.
CLASS_COLOURS_BGR = {
    "noise": (128, 128, 128),
    "pedestrian": (0, 220, 0),
    "group": (0, 200, 255),
    "cyclist": (255, 160, 0),
    "vehicle": (60, 60, 255),
}


def draw_detections(gray: np.ndarray, detections: Sequence, show_noise: bool = True) -> np.ndarray:
    """A BGR copy of ``gray`` with each detection's box and 'class p_target distance' label."""
    img = cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR)
    for det in detections:
        if det.cls == "noise" and not show_noise:
            continue
        x, y, w, h = (int(v) for v in det.box_px)
        colour = CLASS_COLOURS_BGR.get(det.cls, (255, 255, 255))
        thick = 1 if det.cls == "noise" else 2
        cv2.rectangle(img, (x, y), (x + w - 1, y + h - 1), colour, thick)
        label = f"{det.cls} {det.p_target:.2f} {det.features[3]:.0f}m"
        cv2.putText(img, label, (x, max(8, y - 3)), cv2.FONT_HERSHEY_SIMPLEX, 0.3, colour, 1, cv2.LINE_AA)
    return img


def draw_boxes(img_bgr: np.ndarray, boxes: Sequence[tuple[int, int, int, int]], labels: Sequence[str], colour_bgr=(255, 255, 255)) -> np.ndarray:
    """Draw plain boxes (e.g. ground truth) in place and return the image."""
    for (x, y, w, h), label in zip(boxes, labels, strict=True):
        cv2.rectangle(img_bgr, (int(x), int(y)), (int(x + w - 1), int(y + h - 1)), colour_bgr, 1)
        cv2.putText(img_bgr, label, (int(x), int(y + h + 8)), cv2.FONT_HERSHEY_SIMPLEX, 0.3, colour_bgr, 1, cv2.LINE_AA)
    return img_bgr
