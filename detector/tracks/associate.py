"""Which region of this frame continues which track: gated, greedy, in the image and on the ground.

A region may continue a track when it passes the image gate (IoU or centre distance) or the
ground gate (``base_gate_m + gate_per_m * forward_m``, m), and its box area is within
``max_area_ratio`` of the track's; pairs are scored and taken best first.

Design: docs/design/tracks.md (Association)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from operator import itemgetter

from detector.tracks.track import Track


@dataclass(frozen=True)
class Gates:
    """Association gates (see the module docstring)."""

    min_iou: float = 0.1
    max_centre_diag: float = 1.0
    base_gate_m: float = 1.0
    gate_per_m: float = 0.1
    max_area_ratio: float = 8.0

    def __post_init__(self) -> None:
        if not self.max_area_ratio >= 1.0:
            raise ValueError(f"Gates.max_area_ratio: must be >= 1, got {self.max_area_ratio!r}")
        if not 0.0 <= self.min_iou <= 1.0:
            raise ValueError(f"Gates.min_iou: must be in [0, 1], got {self.min_iou!r}")
        for name in ("max_centre_diag", "base_gate_m", "gate_per_m"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"Gates.{name}: must be >= 0, got {getattr(self, name)!r}")


def pair_scores(
    tracks: Sequence[Track], boxes_px: Sequence[Sequence[float]], grounds: Sequence, frame: int, gates: Gates
) -> list[tuple[float, int, int]]:
    """Allowed (score, track index, region index) pairs."""
    # the gates as locals: read in the inner loop, every frame
    min_iou, max_centre_diag, max_ratio = gates.min_iou, gates.max_centre_diag, gates.max_area_ratio
    base_gate_m, gate_per_m = gates.base_gate_m, gates.gate_per_m
    max_d = max(max_centre_diag, 1e-9)
    extents = [(bx, by, bx + bw, by + bh, bw * bh, bx + bw / 2, by + bh / 2) for bx, by, bw, bh in boxes_px]
    pairs = []
    for ti, track in enumerate(tracks):
        px, py, pw, ph = track.predicted_box()
        p_right, p_bottom, p_area = px + pw, py + ph, pw * ph
        pcx, pcy = px + pw / 2, py + ph / 2
        diag = max(math.hypot(pw, ph), 1.0)
        pf, pr = track.predicted_ground(frame)
        gate_m = base_gate_m + gate_per_m * abs(pf)
        for ri, (bx, by, b_right, b_bottom, b_area, bcx, bcy) in enumerate(extents):
            if b_area * max_ratio < p_area or p_area * max_ratio < b_area:
                continue
            dist = math.hypot(pcx - bcx, pcy - bcy) / diag
            iw = min(p_right, b_right) - max(px, bx)
            ih = min(p_bottom, b_bottom) - max(py, by)
            inter = iw * ih if iw > 0 and ih > 0 else 0.0
            union = p_area + b_area - inter
            iou = inter / union if union > 0 else 0.0
            ground = grounds[ri]
            ground_d = math.hypot(ground[0] - pf, ground[1] - pr) if ground is not None else math.inf
            if iou < min_iou and dist > max_centre_diag and ground_d > gate_m:
                continue
            near_img = 1.0 - dist / max_d
            near_ground = 1.0 - ground_d / gate_m if gate_m > 0 else 0.0
            pairs.append((iou + max(near_img, 0.0) + max(near_ground, 0.0), ti, ri))
    return pairs


def associate(
    tracks: Sequence[Track], boxes_px: Sequence[Sequence[float]], grounds: Sequence, frame: int, gates: Gates
) -> list[int]:
    """Each region's track index (-1: none), greedy on ``pair_scores``, best pair first."""
    if not tracks or not boxes_px:
        return [-1] * len(boxes_px)
    return greedy_assign(pair_scores(tracks, boxes_px, grounds, frame, gates), len(boxes_px))


def greedy_assign(pairs: list[tuple[float, int, int]], n_items: int) -> list[int]:
    """Each of ``n_items``' track index (-1: none) from (score, track, item) pairs, best pair first.

    The sort is stable, so tied pairs keep their listed (track-major) order: the same choices as
    taking the argmax of the score matrix again and again with matched rows and columns struck out.
    """
    track_of = [-1] * n_items
    taken = set()
    # reverse keeps the sort stable (tied pairs in their listed order), as a key of -score does, for
    # finite scores (both callers': IoU plus nearnesses clipped at 0); itemgetter is no Python call
    for _, ti, ri in sorted(pairs, key=itemgetter(0), reverse=True):
        if ti not in taken and track_of[ri] < 0:
            track_of[ri] = ti
            taken.add(ti)
    return track_of
