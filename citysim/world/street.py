"""The static street: lanes, sidewalks, kerbs, the lamp chain and scenery.

Pure geometry and reflectances, built once per scenario; the world moves agents
over it and the renderer paints it. Conventions: world frame of docs/design/architecture.md (x
along the street from 0 to ``length_m``, y across it, z up, m). Lane and
sidewalk positions are given by the y of their centre line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from citysim.config.street import ROAD_STEP_M, VERGE_STEP_M
from citysim.world.centreline import Centreline
from citysim.world.placement import agents_in_world
from detector.camera import CameraModel

if TYPE_CHECKING:
    from citysim.config.scenario import Scenario
    from citysim.config.street import ScenerySpec


#: The per-chunk paths (the oracle, the zone metrics) keep a step's lamp zones as the bits of an
#: int64 (bit j: zone j): they take them for streets of up to this many zones, else go agent by agent.
MAX_MASK_ZONES = 62


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
    """One lamp pole with its luminaire and camera (camera already placed in world).

    ``x_m``, ``y_m``: the pole in the world frame; ``s_m``, ``d_m``: in street coordinates
    (default: the same, as on the straight street). Zones are s intervals.
    """

    index: int
    x_m: float
    y_m: float
    pole_height_m: float
    camera: CameraModel  # x_m, y_m, yaw_deg set to this pole
    zone_start_m: float  # the stretch of street (s) this lamp is responsible for
    zone_end_m: float
    back_camera: CameraModel | None = None  # a second camera on the pole (``lamps.camera.back_heading_deg``)
    s_m: float | None = None
    d_m: float | None = None
    rated_power_w: float | None = None  # this lamp's luminaire power (None: the scenario's luminaire)

    @property
    def along_m(self) -> float:
        """The pole's s along the street, m."""
        return self.x_m if self.s_m is None else self.s_m

    @property
    def offset_m(self) -> float:
        """The pole's offset d to the left of the centreline, m."""
        return self.y_m if self.d_m is None else self.d_m


@dataclass(frozen=True)
class CameraSite:
    """One camera of the street and the lamp (pole) it hangs on; ``index`` numbers frames and detectors."""

    index: int
    lamp: int
    camera: CameraModel


@dataclass(frozen=True)
class Street:
    """The street in street coordinates (s along ``centreline`` from 0 to ``length_m``, d to its left;
    lanes, sidewalks, zones, crossings, side entries) with what stands in the world frame (x east,
    y north: the lamps' ``x_m``/``y_m``, their cameras, the scenery). ``centreline`` converts; on the
    straight street (the default) s = x and d = y. Design: docs/design/streets.md."""

    length_m: float
    lanes: tuple[Lane, ...]
    sidewalks: tuple[Sidewalk, ...]
    lamps: tuple[LampSite, ...]
    scenery: tuple[StaticObject, ...] = ()
    kerb_height_m: float = 0.12
    road_ir_reflectance: float = 0.25
    sidewalk_ir_reflectance: float = 0.35
    verge_ir_reflectance: float = 0.2  # grass / gravel beyond the sidewalks
    crossings_x_m: tuple[
        float, ...
    ] = ()  # where pedestrians prefer to cross (the renderer may mark them)
    centreline: Centreline | None = None  # None: the straight street along +x
    side_entries: tuple = ()  # config.street_layout.SideEntrySpec: where road users join mid-street

    def __post_init__(self) -> None:
        if self.centreline is None:
            object.__setattr__(self, "centreline", Centreline.straight(self.length_m))

    # cached: a street never changes, and camera controllers ask for the camera's lamp at every trigger
    @cached_property
    def cameras(self) -> tuple[CameraSite, ...]:
        """Every camera: first each pole's own (camera i on lamp i), then the backward ones in lamp order.

        With one camera per pole, camera and lamp indices coincide.
        """
        own = [CameraSite(i, site.index, site.camera) for i, site in enumerate(self.lamps)]
        back = [site for site in self.lamps if site.back_camera is not None]
        n = len(own)
        return tuple(own + [CameraSite(n + k, site.index, site.back_camera) for k, site in enumerate(back)])

    def in_world(self, agents):
        """Agent snapshots (street coordinates) placed in the world frame (``world.placement``)."""
        return agents_in_world(self.centreline, agents)

    @cached_property
    def camera_lamps(self) -> tuple[int, ...]:
        """The lamp each camera (by camera index) hangs on."""
        return tuple(c.lamp for c in self.cameras)

    @property
    def road_center_y_m(self) -> float:
        """Mean of the lane centre lines (0 without lanes), m."""
        return sum(lane.y_center_m for lane in self.lanes) / len(self.lanes) if self.lanes else 0.0

    def outward(self, sidewalk: Sidewalk) -> float:
        """+1 if the sidewalk's outer (verge) side is toward +y, else -1."""
        return 1.0 if sidewalk.y_center_m >= self.road_center_y_m else -1.0

    def walking_room_m(self, sidewalk: Sidewalk) -> tuple[float, float]:
        """(y_lo, y_hi) walkers may use on this sidewalk: the sidewalk plus the verge and
        road strips they step onto when passing each other, m."""
        half = sidewalk.width_m / 2
        if self.outward(sidewalk) > 0:
            return (
                sidewalk.y_center_m - half - ROAD_STEP_M,
                sidewalk.y_center_m + half + VERGE_STEP_M,
            )
        return sidewalk.y_center_m - half - VERGE_STEP_M, sidewalk.y_center_m + half + ROAD_STEP_M

    @property
    def y_min_m(self) -> float:
        edges = [s.y_center_m - s.width_m / 2 for s in self.sidewalks] + [
            lane.y_center_m - lane.width_m / 2 for lane in self.lanes
        ]
        return min(edges)

    @property
    def y_max_m(self) -> float:
        edges = [s.y_center_m + s.width_m / 2 for s in self.sidewalks] + [
            lane.y_center_m + lane.width_m / 2 for lane in self.lanes
        ]
        return max(edges)


# --------------------------------------------------------------------- builder
#: Random stream id for scenery placement, so scenery never shifts the traffic.
SCENERY_STREAM = 0x5CE7E


def build_street(scenario: Scenario, rng: np.random.Generator | None = None) -> Street:
    """The street of a scenario: lanes, sidewalks, the lamp chain with placed cameras, scenery.

    Scenery is placed at random from ``rng``; by default from the scenery seed
    (``street.scenery.seed``, else the scenario seed), so one scenario always
    has the same street whatever else draws random numbers.
    """
    spec, lamps = scenario.street, scenario.lamps
    if rng is None:
        seed = spec.scenery.seed if spec.scenery.seed is not None else scenario.seed
        rng = np.random.default_rng([seed, SCENERY_STREAM])
    line = Centreline(spec.centreline_points_m)
    sites = tuple(
        _lamp_site(lamps, line, i, s, zone)
        for i, (s, zone) in enumerate(zip(lamps.positions_x_m, lamps.zones(spec.length_m), strict=True))
    )
    street = Street(
        length_m=spec.length_m,
        lanes=tuple(Lane(s.y_center_m, s.width_m, s.direction) for s in spec.lanes),
        sidewalks=tuple(Sidewalk(s.y_center_m, s.width_m) for s in spec.sidewalks),
        lamps=sites,
        kerb_height_m=spec.kerb_height_m,
        crossings_x_m=tuple(spec.crossings_x_m),
        centreline=line,
        side_entries=tuple(spec.side_entries),
    )
    poles = tuple(StaticObject("pole", s.along_m, s.offset_m, 0.2, 0.2, s.pole_height_m, 0.4) for s in sites)
    placed = poles + _place_scenery(street, spec.scenery, poles, rng)  # in street coordinates
    if not line.is_straight_x:
        placed = tuple(_in_world(obj, line) for obj in placed)
    return replace(street, scenery=placed)


def _in_world(obj: StaticObject, line: Centreline) -> StaticObject:
    """A scenery object placed in street coordinates (x_m = s, y_m = d) moved to the world frame.

    Footprints stay boxes along the world axes (the renderer's scenery boxes are axis-aligned):
    length and width swap where the street runs closer to north-south than to east-west.
    """
    x_m, y_m = line.to_xy(obj.x_m, obj.y_m)
    heading = line.heading_rad(obj.x_m)
    if abs(math.sin(heading)) > abs(math.cos(heading)):
        return replace(obj, x_m=x_m, y_m=y_m, length_m=obj.width_m, width_m=obj.length_m)
    return replace(obj, x_m=x_m, y_m=y_m)


def _lamp_site(lamps, line: Centreline, index: int, s_m: float, zone: tuple[float, float]) -> LampSite:
    """Lamp ``index`` at ``s_m`` on ``line``: the pole in the world and its cameras looking along the
    local street direction turned by the camera heading (or the pole's own world heading)."""
    d_m, height_m, power_w, world_heading_deg = lamps.pole_fields(index)
    x_m, y_m = line.to_xy(s_m, d_m)
    base = lamps.camera_model
    if height_m != lamps.pole_height_m and lamps.camera.height_m is None:
        base = base.placed(height_m=height_m)
    street_deg = math.degrees(line.heading_rad(s_m))

    def look(heading_deg: float):
        return heading_deg if line.is_straight_x else street_deg + heading_deg

    if world_heading_deg is not None:
        camera = base.placed(x_m=x_m, y_m=y_m, yaw_deg=world_heading_deg)
    elif lamps.camera.headings_deg is None and line.is_straight_x:
        camera = base.placed(x_m=x_m, y_m=y_m)
    else:
        camera = base.placed(x_m=x_m, y_m=y_m, yaw_deg=look(lamps.heading_of(index)))
    back = lamps.camera.back_heading_deg
    return LampSite(
        index=index, x_m=x_m, y_m=y_m, pole_height_m=height_m, camera=camera,
        zone_start_m=zone[0], zone_end_m=zone[1],
        back_camera=None if back is None else base.placed(x_m=x_m, y_m=y_m, yaw_deg=look(back)),
        s_m=s_m, d_m=d_m, rated_power_w=power_w,
    )  # fmt: skip


@dataclass(frozen=True)
class _SceneryRow:
    """A row of scenery along each side: one of ``kinds`` (kind, width range m or None
    for square, IR reflectance) drawn per object, centred ``offset_m`` outward from
    the verge strip walkers use."""

    kinds: tuple[tuple[str, tuple[float, float] | None, float], ...]
    offset_m: float
    length_m: tuple[float, float]
    height_m: tuple[float, float]


#: Scenery rows by their density field in ``ScenerySpec``, nearest the street first:
#: trees on the verge, garden walls or hedges, cars parked before the houses, houses.
SCENERY_ROWS: dict[str, _SceneryRow] = {
    "trees_per_100m": _SceneryRow((("tree", None, 0.3),), 2.1, (2.0, 4.0), (4.0, 9.0)),
    "walls_per_100m": _SceneryRow(
        (("wall", (0.25, 0.35), 0.45), ("hedge", (0.6, 1.0), 0.25)), 4.6, (5.0, 20.0), (1.0, 1.8)
    ),
    "parked_cars_per_100m": _SceneryRow(
        (("parked_car", (1.4, 1.8), 0.5),), 6.2, (3.7, 4.6), (1.4, 1.8)
    ),
    "buildings_per_100m": _SceneryRow(
        (("building", (8.0, 12.0), 0.35),), 13.0, (8.0, 15.0), (5.0, 9.0)
    ),
}


def _place_scenery(
    street: Street, spec: ScenerySpec, poles: tuple[StaticObject, ...], rng: np.random.Generator
) -> tuple[StaticObject, ...]:
    """Poisson-many objects per row and side, uniform along x; an object that would touch
    its row neighbour or a pole is dropped."""
    out: list[StaticObject] = []
    edges = [
        (lane.y_center_m - lane.width_m / 2, lane.y_center_m + lane.width_m / 2)
        for lane in street.lanes
    ]
    edges += [
        (s.y_center_m - s.width_m / 2, s.y_center_m + s.width_m / 2) for s in street.sidewalks
    ]
    lo_edge, hi_edge = min(e[0] for e in edges), max(e[1] for e in edges)
    for side, y_edge in ((-1.0, lo_edge), (1.0, hi_edge)):
        for field, row in SCENERY_ROWS.items():
            n = rng.poisson(getattr(spec, field) * street.length_m / 100.0)
            xs = np.sort(rng.uniform(0.0, street.length_m, size=n))
            last_end = -np.inf
            for x in xs:
                kind, width_range, reflectance = row.kinds[int(rng.integers(len(row.kinds)))]
                length = float(rng.uniform(*row.length_m))
                width = length if width_range is None else float(rng.uniform(*width_range))
                y = y_edge + side * (VERGE_STEP_M + row.offset_m)
                obj = StaticObject(
                    kind, float(x), y, length, width, float(rng.uniform(*row.height_m)), reflectance
                )
                if x - length / 2 < last_end + 0.5 or any(_overlaps(obj, p, 0.3) for p in poles):
                    continue
                out.append(obj)
                last_end = x + length / 2
    return tuple(out)


def _overlaps(a: StaticObject, b: StaticObject, margin_m: float) -> bool:
    return (
        abs(a.x_m - b.x_m) < (a.length_m + b.length_m) / 2 + margin_m
        and abs(a.y_m - b.y_m) < (a.width_m + b.width_m) / 2 + margin_m
    )
