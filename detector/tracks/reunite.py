"""One object in pieces becomes one region again, before it is classified.

Two rules join pieces: a region inside a continued track's predicted box, and two tracks'
regions that touch, move together and fit a Table 1 class together at least as well as apart.
The union's features are computed again (``detector.features``).

Design: docs/design/tracks.md (Reunification)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from detector.tracks.plausibility import table1_misfit
from detector.tracks.track import Track


@dataclass(frozen=True)
class ReuniteParams:
    """Thresholds of the two rules (see the module docstring)."""

    min_inside_share: float = 0.5
    min_frames: int = 3
    max_gap_share: float = 0.5
    max_velocity_share: float = 0.3
    velocity_slack_px: float = 0.5


def inside_share(box, other) -> float:
    """Share of ``box``'s area that ``other`` covers (boxes x, y, w, h px)."""
    x, y, w, h = box
    ox, oy, ow, oh = other
    iw = min(x + w, ox + ow) - max(x, ox)
    ih = min(y + h, oy + oh) - max(y, oy)
    return iw * ih / max(w * h, 1) if iw > 0 and ih > 0 else 0.0


def _near(a, b, share: float) -> bool:
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    gap_x = max(ax, bx) - min(ax + aw, bx + bw)
    gap_y = max(ay, by) - min(ay + ah, by + bh)
    limit = share * min(ah, bh)
    return gap_x <= limit and gap_y <= limit


def _same_motion(a: Track, b: Track, params: ReuniteParams) -> bool:
    (ax, ay), (bx, by) = a.image_velocity_px, b.image_velocity_px
    faster = max(math.hypot(ax, ay), math.hypot(bx, by))
    return math.hypot(ax - bx, ay - by) <= params.max_velocity_share * faster + params.velocity_slack_px


def union_box(boxes: Sequence[Sequence[float]]) -> list[int]:
    left = min(b[0] for b in boxes)
    top = min(b[1] for b in boxes)
    right = max(b[0] + b[2] for b in boxes)
    bottom = max(b[1] + b[3] for b in boxes)
    return [left, top, right - left, bottom - top]


def fragment_groups(
    tracks: Sequence[Track],
    boxes_px: Sequence[Sequence[float]],
    rows: Sequence[Sequence[float]],
    track_of: Sequence[int],
    union_row,
    params: ReuniteParams,
) -> list[list[int]]:
    """Groups (two or more region indices, the first the one whose track is kept) to join.

    ``union_row(indices)`` gives the feature row of the union of those regions.
    """
    n = len(boxes_px)
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    region_of_track = {t: i for i, t in enumerate(track_of) if t >= 0}
    # rule 1: an unmatched region inside the predicted box of a track another region continues
    for j in range(n):
        if track_of[j] >= 0:
            continue
        for t, i in region_of_track.items():
            if inside_share(boxes_px[j], tracks[t].predicted_box()) >= params.min_inside_share:
                parent[root(j)] = root(i)
                break
    # rule 2: established tracks moving together whose union fits Table 1 at least as well
    established = [i for i in range(n) if track_of[i] >= 0 and tracks[track_of[i]].sightings >= params.min_frames]
    for a, i in enumerate(established):
        for j in established[a + 1 :]:
            if root(i) == root(j) or not _near(boxes_px[i], boxes_px[j], params.max_gap_share):
                continue
            if not _same_motion(tracks[track_of[i]], tracks[track_of[j]], params):
                continue
            parts = min(table1_misfit(rows[i][0], rows[i][1]), table1_misfit(rows[j][0], rows[j][1]))
            union = union_row([i, j])
            if union is not None and table1_misfit(union[0], union[1]) <= parts:
                parent[root(j)] = root(i)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)

    def age(i: int) -> tuple:
        t = track_of[i]
        return (t < 0, -tracks[t].sightings if t >= 0 else 0, i)

    return [sorted(g, key=age) for g in groups.values() if len(g) > 1]
