"""Cameras looking steeply down: a region's size as its footprint on the ground, and a car's
pieces joined into one region by it.

``is_steep`` says which cameras; ``FootprintGeometry`` gives a box's footprint extents and
middle (m, along and across the camera's heading); ``join_groups`` joins a frame's moving
regions that one vehicle could have made; ``continue_inside`` lets a piece left over continue
its track.

Design: docs/design/footprint.md
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from detector.camera import MIN_DEPRESSION_RAD, CameraModel
from detector.classes import TABLE1
from detector.features import RegionGeometry
from detector.tracks.reunite import inside_share

_VEHICLE = TABLE1["vehicle"]


def steep_depression_deg() -> float:
    """Depression (deg below the horizon) beyond which a vehicle going along the view shows
    more length than height: atan(tallest vehicle / shortest vehicle), Table 1 (28.4 deg)."""
    return math.degrees(math.atan(_VEHICLE.height_m[1] / _VEHICLE.length_m[0]))


STEEP_DEPRESSION_DEG = steep_depression_deg()


def is_steep(camera: CameraModel) -> bool:
    """Whether even the camera's top row (image centre column) looks down at least
    ``STEEP_DEPRESSION_DEG`` (see the module docstring)."""
    return camera.tilt_deg - camera.vertical_fov_deg / 2 >= STEEP_DEPRESSION_DEG


@dataclass(frozen=True)
class FootprintParams:
    """The vehicle a union must fit (Table 1's largest, any heading) and the roof plane, m."""

    roof_m: float = _VEHICLE.height_m[1]
    max_extent_m: float = math.hypot(_VEHICLE.length_m[1], _VEHICLE.width_m[1])

    def __post_init__(self) -> None:
        for name in ("roof_m", "max_extent_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"FootprintParams.{name}: must be > 0, got {getattr(self, name)!r}")


class FootprintGeometry:
    """One camera's pixel -> plane constants, for the footprints of region boxes.

    Conventions: boxes are OpenCV ``(x, y, w, h)`` pixels of the distorted frame with pixel
    centres on integers (as ``detector.features``: a box spans [x - 0.5, x + w - 0.5] x
    [y - 0.5, y + h - 0.5]); extents ``(near_m, far_m, left_m, right_m)`` in the camera's ground
    frame (forward along its heading from the pole foot, right of the heading, m), as
    ``detector.tracks.ground``.
    """

    def __init__(self, camera: CameraModel, geometry: RegionGeometry, params: FootprintParams) -> None:
        if not params.roof_m < camera.height_m:
            raise ValueError(f"FootprintGeometry: roof_m {params.roof_m} m must be under the camera's "
                             f"height {camera.height_m} m")  # fmt: skip
        self.geometry, self.params = geometry, params
        self.height_m = camera.height_m
        self.tilt_rad = math.radians(camera.tilt_deg)
        self.sin_tilt, self.cos_tilt = math.sin(self.tilt_rad), math.cos(self.tilt_rad)
        self.cx_px, self.cy_px = camera.cx_px, camera.cy_px
        self.fx_px, self.fy_px = camera.fx_px, camera.fy_px

    def _on_plane(self, u_px: float, v_px: float, plane_m: float) -> tuple[float, float] | None:
        """(forward_m, right_m) where the ray of undistorted pixel (u, v) meets the plane
        ``plane_m`` above the ground; None at or above the horizon."""
        b = (v_px - self.cy_px) / self.fy_px
        if not self.tilt_rad + math.atan(b) > MIN_DEPRESSION_RAD:
            return None
        drop_m = self.height_m - plane_m
        z_cam_m = drop_m / (self.sin_tilt + b * self.cos_tilt)  # depth along the optical axis
        forward_m = z_cam_m * (self.cos_tilt - b * self.sin_tilt)
        return forward_m, z_cam_m * (u_px - self.cx_px) / self.fx_px

    def extents_m(self, boxes_px: Sequence[Sequence[float]]) -> list[tuple[float, float, float, float] | None]:
        """(near_m, far_m, left_m, right_m) of each box's footprint (module docstring); None for
        a box with a corner at or above the horizon."""
        corners = []
        for x, y, w, h in boxes_px:
            left, right, top, bottom = x - 0.5, x + w - 0.5, y - 0.5, y + h - 0.5
            corners += [(left, bottom), (right, bottom), (left, top), (right, top)]
        if not corners:
            return []
        points = self.geometry.undistort(np.array(corners, np.float64)).tolist()
        roof_m = self.params.roof_m
        out: list[tuple[float, float, float, float] | None] = []
        for k in range(len(boxes_px)):
            bl, br, tl, tr = points[4 * k: 4 * k + 4]
            on = [self._on_plane(*bl, 0.0), self._on_plane(*br, 0.0),
                  self._on_plane(*tl, roof_m), self._on_plane(*tr, roof_m)]  # fmt: skip
            if any(p is None for p in on):
                out.append(None)
                continue
            forwards, rights = [p[0] for p in on], [p[1] for p in on]
            out.append((min(forwards), max(forwards), min(rights), max(rights)))
        return out


    def corners_m(self, box_px: Sequence[float], plane_m: float) -> list[tuple[float, float]] | None:
        """(forward_m, right_m) where the rays of the box's bottom-left, bottom-right, top-left and
        top-right corners meet the plane ``plane_m`` above the ground, in that order; None for a
        corner at or above the horizon."""
        x, y, w, h = box_px
        left, right, top, bottom = x - 0.5, x + w - 0.5, y - 0.5, y + h - 0.5
        points = self.geometry.undistort(np.array([(left, bottom), (right, bottom), (left, top), (right, top)],
                                                  np.float64)).tolist()  # fmt: skip
        on = [self._on_plane(u, v, plane_m) for u, v in points]
        return None if any(p is None for p in on) else on

    def centres_m(self, boxes_px: Sequence[Sequence[float]]) -> list[tuple[float, float] | None]:
        """(forward_m, right_m) of the middle of each box's footprint: where a body seen from above
        stands (a car's middle; an upright walker's feet, as his head's ray meets the roof plane
        near them); None as ``extents_m``."""
        return [None if e is None else ((e[0] + e[1]) / 2, (e[2] + e[3]) / 2) for e in self.extents_m(boxes_px)]


def _gap_m(a, b) -> float:
    """Distance between two extents (0 where they overlap or touch), m."""
    gap_forward = max(a[0] - b[1], b[0] - a[1], 0.0)
    gap_right = max(a[2] - b[3], b[2] - a[3], 0.0)
    return math.hypot(gap_forward, gap_right)


def union_box(boxes_px: Sequence[Sequence[float]]) -> list:
    """The box (x, y, w, h px) holding all ``boxes_px``."""
    x0, y0 = min(b[0] for b in boxes_px), min(b[1] for b in boxes_px)
    x1, y1 = max(b[0] + b[2] for b in boxes_px), max(b[1] + b[3] for b in boxes_px)
    return [x0, y0, x1 - x0, y1 - y0]


def join_groups(boxes_px: Sequence[Sequence[float]], extents_m, max_extent_m: float) -> list[list[int]]:
    """Groups (two or more indices, ascending) of regions to join: nearest pairs first (the gap
    between their footprints), while the footprint of the union's box stays within
    ``max_extent_m`` each way. ``extents_m(boxes)`` gives ``FootprintGeometry.extents_m``; a
    region with no footprint joins nothing.

    The union's own box, not the union of the parts' footprints: a piece's bottom edge inside the
    union is no place where the body meets the ground.
    """
    extents = extents_m(boxes_px)
    members = {i: [i] for i in range(len(boxes_px)) if extents[i] is not None}
    group_of = {i: i for i in members}
    pairs = sorted((_gap_m(extents[i], extents[j]), i, j) for i in members for j in members if i < j)
    for _, i, j in pairs:
        gi, gj = group_of[i], group_of[j]
        if gi == gj:
            continue
        joined = extents_m([union_box([boxes_px[k] for k in members[gi] + members[gj]])])[0]
        if joined is None or joined[1] - joined[0] > max_extent_m or joined[3] - joined[2] > max_extent_m:
            continue
        keep, gone = min(gi, gj), max(gi, gj)
        members[keep] += members.pop(gone)
        for k in members[keep]:
            group_of[k] = keep
    return [sorted(m) for m in members.values() if len(m) > 1]


class FootprintJoiner:
    """A steep camera's joining of a frame's regions by footprint (module docstring)."""

    def __init__(self, camera: CameraModel, geometry: RegionGeometry, params: FootprintParams) -> None:
        self.footprints = FootprintGeometry(camera, geometry, params)
        self.geometry, self.params = geometry, params

    def join(self, boxes_px: list, areas_px: list, rows: list) -> tuple[list, list, list]:
        """The regions (boxes px, contour areas px, feature rows) with each group joined into one
        at its first member's place; the lists as given when nothing joins."""
        groups = join_groups(boxes_px, self.footprints.extents_m, self.params.max_extent_m)
        if not groups:
            return boxes_px, areas_px, rows
        boxes_px, areas_px, rows = list(boxes_px), list(areas_px), list(rows)
        drop = set()
        for group in groups:
            box, area = union_box([boxes_px[i] for i in group]), sum(areas_px[i] for i in group)
            row = self.geometry.rows([box], [area])[0]
            if row is None:
                continue
            keep = group[0]
            boxes_px[keep], areas_px[keep], rows[keep] = box, area, row
            drop.update(group[1:])
        kept = [i for i in range(len(boxes_px)) if i not in drop]
        return [boxes_px[i] for i in kept], [areas_px[i] for i in kept], [rows[i] for i in kept]


def continue_inside(tracks: Sequence, boxes_px: Sequence[Sequence[float]], track_of: list[int],
                    min_inside_share: float) -> None:  # fmt: skip
    """Give each region that continues no track (``track_of`` -1) the track, continued by no
    region of this frame, into whose predicted box it falls (at least ``min_inside_share`` of its
    box inside; the first such track); ``track_of`` is changed in place.

    A steep camera's car in pieces: what is left of it in a frame (the body cut off by the frame's
    edge as it leaves, a piece of paint) can be much smaller than its track's box, too small for
    association (``detector.tracks.associate``: the area ratio), but it lies where the car is
    predicted; still regions (ghosts, ``detector.ghosts``) never reach here.
    """
    continued = {t for t in track_of if t >= 0}
    for j, t in enumerate(track_of):
        if t >= 0:
            continue
        for k, track in enumerate(tracks):
            if k in continued:
                continue
            # where it was (at its typical size) or is predicted: a car in pieces has an unsteady
            # image velocity (its box grows and shrinks by pieces), the place it was holds
            x, y, w, h = track.box_px
            tw, th = max(track.typical_size_px[0], w), max(track.typical_size_px[1], h)
            was = (x + w / 2 - tw / 2, y + h - th, tw, th)
            box = boxes_px[j]
            if max(inside_share(box, was), inside_share(box, track.predicted_box())) >= min_inside_share:
                track_of[j] = k
                continued.add(k)
                break
