"""The static street: lanes, sidewalks, kerbs, the lamp chain and scenery.

Pure geometry and reflectances, built once per scenario; the world moves agents
over it and the renderer paints it. Conventions: world frame of DESIGN.md (x
along the street from 0 to ``length_m``, y across it, z up, m). Lane and
sidewalk positions are given by the y of their centre line.
"""

from __future__ import annotations

from dataclasses import dataclass

from detector.camera import CameraModel


@dataclass(frozen=True)
class Lane:
    y_center_m: float
    width_m: float
    direction: int  # +1: traffic moves toward +x; -1: toward -x


@dataclass(frozen=True)
class Sidewalk:
    y_center_m: float
    width_m: float


@dataclass(frozen=True)
class StaticObject:
    """A box standing on the ground (wall, tree crown on a trunk, parked car, pole)."""

    kind: str  # 'wall' | 'building' | 'tree' | 'parked_car' | 'pole' | 'hedge'
    x_m: float  # centre of the footprint
    y_m: float
    length_m: float  # along x
    width_m: float  # along y
    height_m: float
    ir_reflectance: float  # 0..1, near-infrared


@dataclass(frozen=True)
class LampSite:
    """One lamp pole with its luminaire and camera (camera already placed in world)."""

    index: int
    x_m: float
    y_m: float
    pole_height_m: float
    camera: CameraModel  # x_m, y_m, yaw_deg set to this pole
    zone_start_m: float  # the stretch of street (x) this lamp is responsible for
    zone_end_m: float


@dataclass(frozen=True)
class Street:
    length_m: float
    lanes: tuple[Lane, ...]
    sidewalks: tuple[Sidewalk, ...]
    lamps: tuple[LampSite, ...]
    scenery: tuple[StaticObject, ...] = ()
    kerb_height_m: float = 0.12
    road_ir_reflectance: float = 0.25
    sidewalk_ir_reflectance: float = 0.35
    verge_ir_reflectance: float = 0.2  # grass / gravel beyond the sidewalks

    @property
    def y_min_m(self) -> float:
        edges = [s.y_center_m - s.width_m / 2 for s in self.sidewalks] + [l.y_center_m - l.width_m / 2 for l in self.lanes]
        return min(edges)

    @property
    def y_max_m(self) -> float:
        edges = [s.y_center_m + s.width_m / 2 for s in self.sidewalks] + [l.y_center_m + l.width_m / 2 for l in self.lanes]
        return max(edges)
