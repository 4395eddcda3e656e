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


def draw_detections(image: np.ndarray, detections: Sequence, show_noise: bool = True,
                    boxes_px: Sequence[tuple[int, int, int, int]] | None = None,
                    target_threshold: float = 0.5) -> np.ndarray:
    """A BGR copy of ``image`` (gray or BGR) with each detection's box and label: the decision a
    lamp acts on (``detector.detections_csv.decision``: the track's where there is one), drawn
    in its class's colour and labelled '#track class P(target) distance'; a region that is no
    target thin and grey, labelled 'noise'.

    ``boxes_px``: the boxes to draw, one per detection, when ``image`` is not the frame the
    detector saw (e.g. the source video, with ``detector.video.FrameScale.to_source_box``);
    default each detection's own ``box_px``. ``target_threshold``: the detector's, for
    detections on no track.
    """
    from detector.detections_csv import decision

    img = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image.copy()
    # lines and labels grow with the frame, so they read the same on a 1080p video as at 320 px
    size = max(1, round(img.shape[1] / 424))
    boxes = [det.box_px for det in detections] if boxes_px is None else boxes_px
    for det, box in zip(detections, boxes, strict=True):
        target, cls = decision(det, target_threshold)
        if not target and not show_noise:
            continue
        x, y, w, h = (int(v) for v in box)
        colour = CLASS_COLOURS_BGR.get(cls, (255, 255, 255))
        thick = 2 * size if target else size
        cv2.rectangle(img, (x, y), (x + w - 1, y + h - 1), colour, thick)
        p_target = det.p_target if det.track_p_target is None else det.track_p_target
        number = "" if det.track_id is None else f"#{det.track_id} "  # None: a still region
        label = f"{number}{cls} {p_target:.2f} {det.features[3]:.0f}m"
        cv2.putText(img, label, (x, max(8 * size, y - 3 * size)), cv2.FONT_HERSHEY_SIMPLEX, 0.3 * size, colour, size,
                    cv2.LINE_AA)
    return img


def draw_boxes(img_bgr: np.ndarray, boxes: Sequence[tuple[int, int, int, int]], labels: Sequence[str], colour_bgr=(255, 255, 255)) -> np.ndarray:
    """Draw plain boxes (e.g. ground truth) in place and return the image."""
    for (x, y, w, h), label in zip(boxes, labels, strict=True):
        cv2.rectangle(img_bgr, (int(x), int(y)), (int(x + w - 1), int(y + h - 1)), colour_bgr, 1)
        cv2.putText(img_bgr, label, (int(x), int(y + h + 8)), cv2.FONT_HERSHEY_SIMPLEX, 0.3, colour_bgr, 1, cv2.LINE_AA)
    return img_bgr
