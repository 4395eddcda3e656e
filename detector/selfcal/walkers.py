"""Upright moving regions followed through a video in image space: the raw material of self-calibration.

No camera model is known yet, so nothing here is metric: the segmenter (``detector.segment``,
whole frames) finds the moving regions, those clear of the frame's edge and at least
``MIN_ASPECT`` times as tall as wide (a person standing or walking, seen from a pole) are
joined frame to frame by overlap (``_continues``), tracks of one walker lost for up to
``LINK_GAP_S`` are linked (``link_fragments``), and each track is a list of sightings: the column of the
region's centre and the rows of its top and bottom edges (pixel-centre convention: the box
rows y .. y+h-1 have edges at y - 0.5 and y + h - 0.5), each moved ``GROWN_PX`` inwards: the
segmenter's joining dilation grows every region by that much on each side.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from detector.segment import Segmenter, SegmenterParams

#: height / width of a region that may be a person, px/px (Table 1: 1.15-2 m tall, 0.3-0.64 m wide)
MIN_ASPECT = 1.6
#: smallest region height worth measuring, px
MIN_HEIGHT_PX = 12
#: smallest region kept by the segmenter, share of the frame's pixels (a far walker is small)
MIN_AREA_FRACTION = 0.0002
#: frames a track may go unseen and still be continued
MAX_GAP_FRAMES = 8
#: a track starting at most this long after another ended, where it ended, continues it, s
LINK_GAP_S = 1.0
#: smallest share of a region's box inside a track's grown last box for it to continue the track
MIN_INSIDE = 0.6
#: a region continuing a track is at most this many times taller or shorter than the track's last box
MAX_HEIGHT_RATIO = 1.5
_PARAMS = SegmenterParams(min_area_fraction=MIN_AREA_FRACTION)
#: how far the segmenter's dilation grows a region on each side, px
GROWN_PX = _PARAMS.dilate_iterations * (_PARAMS.open_kernel_px // 2)


@dataclass
class ImageTrack:
    """One upright region followed through frames; ``sightings`` rows are (frame, centre column
    px, top edge row px, bottom edge row px, width px)."""

    last_box: tuple[int, int, int, int]
    last_frame: int
    sightings: list[tuple[float, float, float, float]] = field(default_factory=list)

    def add(self, frame: int, box: tuple[int, int, int, int]) -> None:
        x, y, w, h = box
        self.sightings.append((frame, x + (w - 1) / 2, y - 0.5 + GROWN_PX, y + h - 0.5 - GROWN_PX, w - 2 * GROWN_PX))
        self.last_box, self.last_frame = box, frame


def _iou(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> float:
    ix = max(0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    iy = max(0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    inter = ix * iy
    return inter / (a[2] * a[3] + b[2] * b[3] - inter) if inter else 0.0


def _continues(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> float:
    """How well box ``a`` continues box ``b`` (a track's last box), 0 when it cannot: ``a`` lies
    mostly (``MIN_INSIDE``) within ``b`` grown by a quarter of its height on every side (a walker
    moves between sightings) and its height is within ``MAX_HEIGHT_RATIO`` of ``b``'s (a leg or
    a head lost for a frame, no more); else their overlap (intersection over union), at least
    a small positive number, so the nearest of several candidates wins."""
    m = max(2, b[3] // 4)
    grown = (b[0] - m, b[1] - m, b[2] + 2 * m, b[3] + 2 * m)
    ix = max(0, min(a[0] + a[2], grown[0] + grown[2]) - max(a[0], grown[0]))
    iy = max(0, min(a[1] + a[3], grown[1] + grown[3]) - max(a[1], grown[1]))
    if ix * iy < MIN_INSIDE * a[2] * a[3] or not 1 / MAX_HEIGHT_RATIO <= a[3] / b[3] <= MAX_HEIGHT_RATIO:
        return 0.0
    return max(_iou(a, b), 1e-6)


def join_stacked(boxes: list, edges: list) -> list[tuple[tuple[int, int, int, int], bool]]:
    """Join regions stacked one above the other (a walker's torso and legs segmented apart): boxes
    whose columns overlap by half the narrower one's width and whose rows overlap or are at most
    ``gap`` = a fifth of the taller one's height apart; returns (box, touches the frame's edge)."""
    items = [(tuple(int(v) for v in b), bool(e)) for b, e in zip(boxes, edges, strict=True)]
    joined = True
    while joined and len(items) > 1:
        joined = False
        for i in range(len(items)):
            for j in range(i + 1, len(items)):
                (a, ea), (b, eb) = items[i], items[j]
                overlap = min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0])
                gap = max(a[1], b[1]) - min(a[1] + a[3], b[1] + b[3])
                if overlap >= 0.5 * min(a[2], b[2]) and gap <= max(a[3], b[3]) / 5:
                    x0, y0 = min(a[0], b[0]), min(a[1], b[1])
                    x1, y1 = max(a[0] + a[2], b[0] + b[2]), max(a[1] + a[3], b[1] + b[3])
                    items[i] = ((x0, y0, x1 - x0, y1 - y0), ea or eb)
                    del items[j]
                    joined = True
                    break
            if joined:
                break
    return items


def link_fragments(tracks: list[np.ndarray], max_gap_frames: int) -> list[np.ndarray]:
    """Join tracks that are one walker lost for a while (hidden behind another, merged with him):
    a track starting at most ``max_gap_frames`` after another ended, whose first sighting's foot
    row and centre column are within half the other's last height of its last ones and whose
    height is within ``MAX_HEIGHT_RATIO`` of it, continues it (the one that ended last, where several could).
    ``tracks``: (N, 5) sighting arrays as ``upright_tracks`` returns them."""
    out: list[np.ndarray] = []
    for t in sorted(tracks, key=lambda t: t[0, 0]):
        f, col, top, bot, _ = t[0]
        best = None
        for i, a in enumerate(out):
            lf, lcol, ltop, lbot, _ = a[-1]
            reach = (lbot - ltop) / 2
            if (0 < f - lf <= max_gap_frames and abs(col - lcol) <= reach and abs(bot - lbot) <= reach
                    and 1 / MAX_HEIGHT_RATIO <= (bot - top) / (lbot - ltop) <= MAX_HEIGHT_RATIO):
                if best is None or lf > out[best][-1, 0]:
                    best = i
        if best is None:
            out.append(t)
        else:
            out[best] = np.vstack([out[best], t])
    return out


def upright_tracks(frames: Iterable[np.ndarray], fps: float, min_sightings: int = 8) -> list[np.ndarray]:
    """Follow the upright moving regions of ``frames`` (uint8 grayscale, one size) at ``fps``
    frames/s; returns each track of at least ``min_sightings`` sightings as an (N, 4) array
    (frame, centre column px, top edge row px, bottom edge row px, width px).

    The first second is skipped: the background model is still learning the scene.
    """
    segmenter = Segmenter(_PARAMS, fps)
    warm_up = int(round(fps))
    active: list[ImageTrack] = []
    done: list[ImageTrack] = []
    for k, gray in enumerate(frames):
        regions = segmenter.apply(gray)
        if k < warm_up or not len(regions):
            continue
        boxes = join_stacked(regions.boxes_px.tolist(), regions.touches_border.tolist())
        candidates = [box for box, edge in boxes if not edge and box[3] >= MIN_HEIGHT_PX and box[3] >= MIN_ASPECT * box[2]]
        live = [t for t in active if k - t.last_frame <= MAX_GAP_FRAMES]
        done.extend(t for t in active if k - t.last_frame > MAX_GAP_FRAMES)
        # the best-overlapping (track, region) pairs first: a track and a region are paired once
        pairs = sorted(((_continues(box, t.last_box), i, j) for i, t in enumerate(live)
                        for j, box in enumerate(candidates)), reverse=True)
        used_t, used_b = set(), set()
        for score, i, j in pairs:
            if score > 0 and i not in used_t and j not in used_b:
                live[i].add(k, candidates[j])
                used_t.add(i)
                used_b.add(j)
        still = live
        candidates = [box for j, box in enumerate(candidates) if j not in used_b]
        for box in candidates:
            track = ImageTrack(box, k)
            track.add(k, box)
            still.append(track)
        active = still
    tracks = link_fragments([np.array(t.sightings) for t in (*done, *active)], int(round(LINK_GAP_S * fps)))
    return [t for t in tracks if len(t) >= min_sightings]
