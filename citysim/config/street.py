"""Scenario schema for the static street and the lamp chain (with the lamps' camera).

Conventions: world frame of docs/design/architecture.md (x along the street from 0 to
``length_m``, y across it, z up, metres). Lanes and sidewalks are given by the
y of their centre line and their width.
"""

from __future__ import annotations

from pathlib import Path

import yaml
from pydantic import (
    Field,
    PrivateAttr,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from citysim.config.base import FieldPathError, Spec
from citysim.config.street_layout import CentrelineMixin, PoleSpec, check_poles, check_side_entries
from detector.camera import CameraModel

#: Smallest lane that holds the widest car of Table 1 (1.8 m) with clearance.
MIN_LANE_WIDTH_M = 2.5
#: Crossings keep this far from the street ends, where agents enter.
CROSSING_END_CLEARANCE_M = 10.0
#: Walkers passing each other may step this far beyond a sidewalk's outer edge (verge), m.
VERGE_STEP_M = 0.5
#: ... and this far off the kerb into the road, m.
ROAD_STEP_M = 1.0


class LaneSpec(Spec):
    y_center_m: float = Field(ge=-100, le=100)
    width_m: float = Field(ge=MIN_LANE_WIDTH_M, le=6.0)
    direction: int = Field(description="+1: traffic moves toward +x; -1: toward -x")

    @field_validator("direction")
    @classmethod
    def _unit(cls, v: int) -> int:
        if v not in (1, -1):
            raise ValueError(f"direction must be +1 (toward +x) or -1 (toward -x), got {v}")
        return v


class SidewalkSpec(Spec):
    y_center_m: float = Field(ge=-100, le=100)
    width_m: float = Field(ge=1.0, le=10.0)


class ScenerySpec(Spec):
    """Static scenery beside the street, placed at random from ``seed`` (default: the scenario seed)."""

    trees_per_100m: float = Field(default=4.0, ge=0, le=50)
    walls_per_100m: float = Field(default=3.0, ge=0, le=50)
    parked_cars_per_100m: float = Field(default=2.0, ge=0, le=50)
    buildings_per_100m: float = Field(default=3.0, ge=0, le=20)
    seed: int | None = Field(default=None, ge=0)


class StreetSpec(CentrelineMixin):
    """The street. With ``centreline_m`` (``config.street_layout``) the fields named x/y here are
    street coordinates: ``s`` metres along the centreline and ``d`` metres to its left (on the
    straight street without it, s = x and d = y). Design: docs/design/streets.md."""

    length_m: float = Field(ge=30, le=5000)
    lanes: tuple[LaneSpec, ...] = ()
    sidewalks: tuple[SidewalkSpec, ...] = ()
    crossings_x_m: tuple[float, ...] = Field(
        default=(), description="where pedestrians prefer to cross, m"
    )
    kerb_height_m: float = Field(default=0.12, ge=0, le=0.5)
    scenery: ScenerySpec = ScenerySpec()

    @property
    def road_center_y_m(self) -> float:
        return sum(lane.y_center_m for lane in self.lanes) / len(self.lanes) if self.lanes else 0.0

    @model_validator(mode="after")
    def _layout(self) -> StreetSpec:
        strips = [("lanes", i, s) for i, s in enumerate(self.lanes)] + [
            ("sidewalks", i, s) for i, s in enumerate(self.sidewalks)
        ]
        for a in range(len(strips)):
            for b in range(a):
                (ka, ia, sa), (kb, ib, sb) = strips[a], strips[b]
                lo_a, hi_a = sa.y_center_m - sa.width_m / 2, sa.y_center_m + sa.width_m / 2
                lo_b, hi_b = sb.y_center_m - sb.width_m / 2, sb.y_center_m + sb.width_m / 2
                if min(hi_a, hi_b) - max(lo_a, lo_b) > 1e-6:
                    raise FieldPathError(
                        (ka, ia, "y_center_m"),
                        f"{ka}[{ia}] (y {lo_a:g}..{hi_a:g} m) overlaps {kb}[{ib}] (y {lo_b:g}..{hi_b:g} m); "
                        "lanes and sidewalks may touch but not overlap",
                    )
        lo, hi = CROSSING_END_CLEARANCE_M, self.length_m - CROSSING_END_CLEARANCE_M
        for i, x in enumerate(self.crossings_x_m):
            if not lo <= x <= hi:
                raise FieldPathError(
                    ("crossings_x_m", i),
                    f"crossing at x={x:g} m must lie within {lo:g}..{hi:g} m (got {x:g})",
                )
        check_side_entries(self.side_entries, self.length_m)
        if self.crossings_x_m and not self.has_both_sides:
            raise FieldPathError(
                ("crossings_x_m",),
                "crossings need a sidewalk on each side of the road (street.sidewalks)",
            )
        return self

    @property
    def has_both_sides(self) -> bool:
        c = self.road_center_y_m
        return any(s.y_center_m < c for s in self.sidewalks) and any(
            s.y_center_m > c for s in self.sidewalks
        )

    def pole_clearance_problem(self, y_m: float) -> str | None:
        """Why a pole at ``y_m`` would stand in someone's way, or None.

        Poles stand outside the lanes, and outside the sidewalks plus the strips
        walkers step onto when passing (``VERGE_STEP_M`` beyond the outer edge,
        ``ROAD_STEP_M`` into the road at the kerb).
        """
        for i, lane in enumerate(self.lanes):
            if abs(y_m - lane.y_center_m) < lane.width_m / 2:
                return f"y_m={y_m:g} m lies inside lane {i} (y {lane.y_center_m - lane.width_m / 2:g}..{lane.y_center_m + lane.width_m / 2:g} m)"
        c = self.road_center_y_m
        for i, sw in enumerate(self.sidewalks):
            outward = 1.0 if sw.y_center_m >= c else -1.0
            lo = sw.y_center_m - sw.width_m / 2 - (VERGE_STEP_M if outward < 0 else ROAD_STEP_M)
            hi = sw.y_center_m + sw.width_m / 2 + (VERGE_STEP_M if outward > 0 else ROAD_STEP_M)
            if lo < y_m < hi:
                return (
                    f"y_m={y_m:g} m is within sidewalk {i}'s walking room (y {lo:g}..{hi:g} m: the sidewalk "
                    f"plus {VERGE_STEP_M:g} m of verge walkers step onto); stand the poles beyond it"
                )
        return None


class LuminaireSpec(Spec):
    """One lamp's luminaire and smart-sensing power model."""

    rated_power_w: float = Field(default=60.0, gt=0, le=2000)
    dim_level: float = Field(default=0.2, ge=0, le=1, description="level with nobody around, 0..1")
    standby_power_w: float = Field(default=0.5, ge=0, le=100, description="driver power when off")
    ramp_up_s: float = Field(default=0.3, ge=0, le=60)
    fade_s: float = Field(default=1.0, ge=0, le=600)
    hold_s: float = Field(
        default=30.0, ge=0, le=3600, description="stay lit this long after the last detection"
    )
    sensing_power_w: float = Field(
        default=5.0, ge=0, le=100, description="camera + board + IR emitter"
    )


#: CameraModel fields a lamp camera may set inline (its pose comes from the pole).
CAMERA_INTRINSIC_FIELDS = (
    "tilt_deg", "focal_mm", "sensor_w_mm", "sensor_h_mm", "width_px", "height_px",
    "k1", "k2", "p1", "p2", "k3", "fps", "name",
)  # fmt: skip
_CAMERA_POSE_FIELDS = ("height_m", "x_m", "y_m", "yaw_deg")


class LampCameraSpec(Spec):
    """The camera on every lamp: a camera file and/or inline fields; inline fields win.

    ``file`` is relative to the scenario file. A camera file's own pose (its
    testbed height, x, y, yaw) is not used: the camera hangs on each pole at
    ``height_m`` (default: ``lamps.pole_height_m``) looking along ``heading_deg``
    (deg CCW from the local street direction toward increasing s: from +x on a straight street;
    a surveyed pole's own ``heading_deg`` is a world heading instead).
    """

    file: str | None = None
    heading_deg: float = Field(default=0.0, ge=-360, le=360)
    headings_deg: tuple[float, ...] | None = Field(
        default=None,
        description="one heading per lamp (deg CCW from the street direction), overriding heading_deg: e.g. the "
        "first camera looking back at the street's approach",
    )
    back_heading_deg: float | None = Field(
        default=None,
        ge=-360,
        le=360,
        description="a second camera on every pole looking this way (deg CCW from the street direction), e.g. 188: "
        "back along -x, turned 8 deg toward the road, so the stretch under each pole is seen",
    )
    height_m: float | None = Field(default=None, gt=0, le=30)
    tilt_deg: float | None = None
    focal_mm: float | None = None
    sensor_w_mm: float | None = None
    sensor_h_mm: float | None = None
    width_px: int | None = None
    height_px: int | None = None
    k1: float | None = None
    k2: float | None = None
    p1: float | None = None
    p2: float | None = None
    k3: float | None = None
    fps: float | None = None
    name: str | None = None

    @field_validator("file")
    @classmethod
    def _resolve(cls, v: str | None, info: ValidationInfo) -> str | None:
        if v is None:
            return None
        path = Path(v)
        base = (info.context or {}).get("base_dir")
        if not path.is_absolute() and base is not None:
            path = Path(base) / path
        if not path.is_file():
            raise ValueError(
                f"camera file {str(path)!r} not found (a path relative to the scenario file)"
            )
        return str(path.resolve())

    def file_fields(self) -> dict:
        """The camera file's intrinsic fields (empty without a file)."""
        if self.file is None:
            return {}
        try:
            data = yaml.safe_load(Path(self.file).read_text())
        except (OSError, yaml.YAMLError) as exc:
            raise FieldPathError(
                ("file",), f"cannot read camera file {self.file!r} ({exc})"
            ) from None
        if not isinstance(data, dict):
            raise FieldPathError(
                ("file",), f"camera file {self.file!r} must be a YAML mapping of CameraModel fields"
            )
        unknown = sorted(set(data) - set(CAMERA_INTRINSIC_FIELDS) - set(_CAMERA_POSE_FIELDS))
        if unknown:
            raise FieldPathError(
                ("file",),
                f"camera file {self.file!r}: unknown field(s) {', '.join(unknown)}; "
                f"valid: {', '.join(CAMERA_INTRINSIC_FIELDS + _CAMERA_POSE_FIELDS)}",
            )
        return {k: v for k, v in data.items() if k in CAMERA_INTRINSIC_FIELDS}


class LampsSpec(Spec):
    """The lamp chain: explicit pole positions ``x_m`` or ``count`` x ``spacing_m`` from ``first_x_m``.

    Each lamp is responsible for the stretch of street between the half-way
    points to its neighbours (the first from x = 0, the last to the street end).
    """

    x_m: tuple[float, ...] | None = None
    count: int | None = Field(default=None, ge=1, le=1000)
    spacing_m: float | None = Field(default=None, gt=0, le=1000)
    first_x_m: float | None = Field(default=None, ge=0)
    y_m: float | None = Field(
        default=None, ge=-100, le=100, description="offset d of the poles (optional with poles)"
    )
    poles: tuple[PoleSpec, ...] | None = None
    pole_height_m: float = Field(default=6.0, gt=0, le=30)
    luminaire: LuminaireSpec = LuminaireSpec()
    camera: LampCameraSpec

    _camera_model: CameraModel = PrivateAttr()

    @model_validator(mode="after")
    def _chain_and_camera(self) -> LampsSpec:
        if self.poles is not None:
            if self.x_m is not None or self.count is not None or self.spacing_m is not None:
                raise FieldPathError(("poles",), "give either poles (surveyed lamps) or x_m / count + spacing_m, not both")
            check_poles(self.poles)
        elif self.y_m is None:
            raise FieldPathError(("y_m",), "the poles' offset y_m is required (or give surveyed lamps as poles)")
        elif self.x_m is not None:
            if self.count is not None or self.spacing_m is not None or self.first_x_m is not None:
                raise FieldPathError(
                    ("x_m",), "give either x_m (explicit positions) or count + spacing_m, not both"
                )
            if not self.x_m:
                raise FieldPathError(("x_m",), "needs at least one lamp position")
            for i in range(1, len(self.x_m)):
                if self.x_m[i] - self.x_m[i - 1] < 1.0:
                    raise FieldPathError(
                        ("x_m", i),
                        f"positions must increase by >= 1 m, got {self.x_m[i - 1]:g} then {self.x_m[i]:g}",
                    )
        elif self.count is None or self.spacing_m is None:
            missing = "count" if self.count is None else "spacing_m"
            raise FieldPathError(
                (missing,), "give either x_m (explicit positions) or both count and spacing_m"
            )
        headings = self.camera.headings_deg
        if headings is not None:
            n = len(self.positions_x_m)
            if len(headings) != n:
                raise FieldPathError(("camera", "headings_deg"), f"one heading per lamp: {n} lamps, got {len(headings)}")
            for i, h in enumerate(headings):
                if not -360 <= h <= 360:
                    raise FieldPathError(("camera", "headings_deg", i), f"must be in -360..360 deg, got {h:g}")
        self._camera_model = self._build_camera()
        return self

    @property
    def cameras_per_pole(self) -> int:
        """1, or 2 with a backward camera (``camera.back_heading_deg``) on every pole."""
        return 1 if self.camera.back_heading_deg is None else 2

    def heading_of(self, lamp_index: int) -> float:
        """Lamp ``lamp_index``'s camera heading, deg CCW from the local street direction (toward +s)."""
        headings = self.camera.headings_deg
        return self.camera.heading_deg if headings is None else headings[lamp_index]

    def pole_fields(self, lamp_index: int) -> tuple[float, float, float, float | None]:
        """Lamp ``lamp_index``'s (d_m offset, pole height_m, rated_power_w, world heading_deg or None)."""
        pole = None if self.poles is None else self.poles[lamp_index]
        if pole is None:
            return self.y_m, self.pole_height_m, self.luminaire.rated_power_w, None
        height = self.pole_height_m if pole.height_m is None else pole.height_m
        power = self.luminaire.rated_power_w if pole.rated_power_w is None else pole.rated_power_w
        return pole.d_m, height, power, pole.heading_deg

    def _build_camera(self) -> CameraModel:
        spec = self.camera
        merged = spec.file_fields()
        inline = {
            k: getattr(spec, k) for k in CAMERA_INTRINSIC_FIELDS if getattr(spec, k) is not None
        }
        from_file = set(merged) - set(inline)
        merged.update(inline)
        merged.update(height_m=spec.height_m or self.pole_height_m, yaw_deg=spec.heading_deg)
        try:
            return CameraModel.model_validate(merged)
        except ValidationError as exc:
            err = exc.errors()[0]
            field = (
                err["loc"][0] if err["loc"] else "tilt_deg"
            )  # the model-level check is the ground check
            msg = err["msg"].removeprefix("Value error, ")
            got = f" (got {err['input']!r})" if err["loc"] and err["type"] != "missing" else ""
            origin = f" (from camera file {spec.file})" if field in from_file else ""
            path = (
                ("pole_height_m",)
                if field == "height_m" and spec.height_m is None
                else ("camera", field)
            )
            raise FieldPathError(path, f"{msg}{got}{origin}") from None

    @property
    def positions_x_m(self) -> tuple[float, ...]:
        """Each lamp's s along the street, m."""
        if self.poles is not None:
            return tuple(p.s_m for p in self.poles)
        if self.x_m is not None:
            return self.x_m
        first = self.first_x_m if self.first_x_m is not None else self.spacing_m / 2
        return tuple(first + i * self.spacing_m for i in range(self.count))

    @property
    def camera_model(self) -> CameraModel:
        """The lamp camera at pole height and heading, standing at x = y = 0 (place it per pole)."""
        return self._camera_model

    def zones(self, length_m: float) -> tuple[tuple[float, float], ...]:
        """(start, end) x of each lamp's zone: half-way to the neighbours, clipped to the street, m.

        The end lamps reach half a spacing beyond themselves, no further: street beyond the chain is
        an approach lit by other streets' lamps (not simulated), where the end cameras can see what
        comes. A lone lamp is responsible for the whole street.
        """
        xs = self.positions_x_m
        if len(xs) == 1:
            return ((0.0, length_m),)
        first = max(0.0, xs[0] - (xs[1] - xs[0]) / 2)
        last = min(length_m, xs[-1] + (xs[-1] - xs[-2]) / 2)
        cuts = [first] + [(a + b) / 2 for a, b in zip(xs[:-1], xs[1:], strict=True)] + [last]
        return tuple((cuts[i], cuts[i + 1]) for i in range(len(xs)))
