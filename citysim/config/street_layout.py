"""Scenario schema for real streets: the centreline polyline, its origin, side entries, surveyed poles.

Conventions: a local east/north frame in metres (x east, y north, z up). A road user's street
coordinates are ``s`` (metres along the centreline from its first point) and ``d`` (metres to the
LEFT of the centreline, looking along increasing ``s``). The straight street of a scenario without
``centreline_m`` is the centreline ``[[0, 0], [length_m, 0]]``: s = x, d = y.
"""

from __future__ import annotations

import difflib
import math
from typing import Literal

from pydantic import Field, field_validator, model_validator

from citysim.config.base import FieldPathError, Spec
from citysim.config.kinds import AGENT_KINDS

#: Consecutive centreline points closer than this are rejected, m.
MIN_POINT_SPACING_M = 0.5
#: A centreline may turn at most this much at one vertex, deg.
MAX_TURN_DEG = 150.0
#: ``length_m`` given beside ``centreline_m`` must equal the polyline's length within this, m.
LENGTH_TOLERANCE_M = 0.5
#: The shares of one class over every side entry sum to at most this (the rest uses the street ends).
MAX_SIDE_SHARE = 0.9


def polyline_length_m(points: tuple[tuple[float, float], ...]) -> float:
    """Length of the polyline through ``points`` ((x, y) in metres), m."""
    return sum(math.dist(a, b) for a, b in zip(points[:-1], points[1:], strict=True))


def _segments_cross(a, b, c, d) -> bool:
    """Do the closed segments ab and cd (points (x, y), m) share a point?"""

    def orient(p, q, r) -> float:
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    def on(p, q, r) -> bool:  # r on segment pq, given collinear
        return min(p[0], q[0]) <= r[0] <= max(p[0], q[0]) and min(p[1], q[1]) <= r[1] <= max(p[1], q[1])

    o1, o2, o3, o4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return any(
        o == 0 and on(p, q, r)
        for o, p, q, r in ((o1, a, b, c), (o2, a, b, d), (o3, c, d, a), (o4, c, d, b))
    )


def centreline_problem(points: tuple[tuple[float, float], ...]) -> tuple[int, str] | None:
    """(index of the offending point, why) if ``points`` is no usable centreline, else None.

    Rejected: fewer than 2 points, consecutive points under ``MIN_POINT_SPACING_M`` apart, a turn
    sharper than ``MAX_TURN_DEG`` at one vertex, segments that cross (non-adjacent ones sharing any
    point). Points are (x east, y north) in metres.
    """
    if len(points) < 2:
        return 0, f"needs at least 2 points [x_m, y_m], got {len(points)}"
    for i in range(1, len(points)):
        gap_m = math.dist(points[i - 1], points[i])
        if gap_m < MIN_POINT_SPACING_M:
            return i, (
                f"point {i} is {gap_m:.3g} m from point {i - 1}; consecutive points must be "
                f">= {MIN_POINT_SPACING_M:g} m apart"
            )
    for i in range(1, len(points) - 1):
        (x0, y0), (x1, y1), (x2, y2) = points[i - 1], points[i], points[i + 1]
        turn_deg = abs(math.degrees(math.atan2(
            (x1 - x0) * (y2 - y1) - (y1 - y0) * (x2 - x1), (x1 - x0) * (x2 - x1) + (y1 - y0) * (y2 - y1)
        )))  # fmt: skip
        if turn_deg > MAX_TURN_DEG:
            return i, f"turns {turn_deg:.1f} deg at point {i}; at most {MAX_TURN_DEG:g} deg per vertex"
    n = len(points) - 1  # segments
    for i in range(n):
        for j in range(i + 2, n):
            if _segments_cross(points[i], points[i + 1], points[j], points[j + 1]):
                return j, f"segment {j} (points {j}..{j + 1}) crosses segment {i}: the street intersects itself"
    return None


class OriginSpec(Spec):
    """Where local (0, 0) lies on Earth (informational: maps, the year's site default)."""

    latitude_deg: float = Field(ge=-90, le=90)
    longitude_deg: float = Field(ge=-180, le=180)
    crs: str = Field(default="EPSG:4326", description="the CRS the source was in (informational)")


SIDE_ENTRY_KINDS = ("junction", "path", "driveway")
#: Other names a side entry's share may use for a road-user kind.
CLASS_ALIASES = {"car": "vehicle", "bicycle": "cyclist", "pedestrians": "pedestrian"}


class SideEntrySpec(Spec):
    """A point along the street where a share of each class joins and leaves it from the side."""

    s_m: float = Field(ge=0, description="where along the centreline, m")
    side: Literal["left", "right"] = Field(description="which side of the street the entry is on")
    name: str | None = None
    kind: Literal["junction", "path", "driveway"] = "junction"
    share: dict[str, float] = Field(
        default_factory=dict, description="share of each class's arrivals that join here (0..0.9)"
    )

    @field_validator("share")
    @classmethod
    def _shares(cls, v: dict[str, float]) -> dict[str, float]:
        v = {CLASS_ALIASES.get(name, name): share for name, share in v.items()}
        for name, share in v.items():
            if name not in AGENT_KINDS:
                near = difflib.get_close_matches(name, AGENT_KINDS, n=1)
                hint = f" (did you mean {near[0]!r}?)" if near else ""
                raise ValueError(f"unknown class {name!r} in share{hint}; valid: {', '.join(AGENT_KINDS)}")
            if not 0 <= share <= MAX_SIDE_SHARE:
                raise ValueError(f"share of {name!r} must be in 0..{MAX_SIDE_SHARE:g}, got {share:g}")
        return v

    @property
    def side_sign(self) -> float:
        """+1 for an entry on the left (d > 0), -1 on the right."""
        return 1.0 if self.side == "left" else -1.0


def check_side_entries(entries: tuple[SideEntrySpec, ...], length_m: float) -> None:
    """Raise ``FieldPathError`` (path below ``street``) unless every entry lies on the street and
    each class's shares sum to at most ``MAX_SIDE_SHARE``."""
    totals: dict[str, float] = {}
    for i, entry in enumerate(entries):
        if entry.s_m > length_m:
            raise FieldPathError(
                ("side_entries", i, "s_m"), f"s_m={entry.s_m:g} m lies beyond the street end ({length_m:g} m)"
            )
        for name, share in entry.share.items():
            totals[name] = totals.get(name, 0.0) + share
    for name, total in totals.items():
        if total > MAX_SIDE_SHARE + 1e-9:
            raise FieldPathError(
                ("side_entries",),
                f"the shares of {name!r} sum to {total:g}; at most {MAX_SIDE_SHARE:g} (the rest enters at the ends)",
            )


class PoleSpec(Spec):
    """One surveyed lamp: where it stands in street coordinates, and what differs from the chain's defaults."""

    s_m: float = Field(ge=0, description="along the centreline, m")
    d_m: float = Field(ge=-100, le=100, description="offset to the left (+) or right (-) of the centreline, m")
    height_m: float | None = Field(default=None, gt=0, le=30, description="default lamps.pole_height_m")
    rated_power_w: float | None = Field(
        default=None, gt=0, le=2000, description="default lamps.luminaire.rated_power_w"
    )
    heading_deg: float | None = Field(
        default=None,
        ge=-360,
        le=360,
        description="camera heading, deg CCW from +x (east) in the world frame; default: along the "
        "street toward increasing s (plus lamps.camera.heading_deg)",
    )
    ref: str | None = None


def check_poles(poles: tuple[PoleSpec, ...]) -> None:
    """Raise ``FieldPathError`` (path below ``lamps``) unless there is a pole and their s increases by >= 1 m."""
    if not poles:
        raise FieldPathError(("poles",), "needs at least one pole")
    for i in range(1, len(poles)):
        if poles[i].s_m - poles[i - 1].s_m < 1.0:
            raise FieldPathError(
                ("poles", i, "s_m"),
                f"poles must be in order of s, >= 1 m apart: got {poles[i - 1].s_m:g} then {poles[i].s_m:g}",
            )


class CentrelineMixin(Spec):
    """The optional real-street fields of ``street`` (a mixin of ``StreetSpec``)."""

    centreline_m: tuple[tuple[float, float], ...] | None = Field(
        default=None, description="the centreline polyline [[x_m, y_m], ...] in local east/north metres"
    )
    origin: OriginSpec | None = None
    source: str | None = None
    side_entries: tuple[SideEntrySpec, ...] = ()

    @model_validator(mode="before")
    @classmethod
    def _length_from_centreline(cls, data):
        if isinstance(data, dict) and data.get("centreline_m") is not None:
            try:
                points = tuple((float(x), float(y)) for x, y in data["centreline_m"])
            except (TypeError, ValueError):
                raise FieldPathError(("centreline_m",), "must be a list of [x_m, y_m] pairs") from None
            problem = centreline_problem(points)
            if problem:
                raise FieldPathError(("centreline_m", problem[0]), problem[1])
            total_m = polyline_length_m(points)
            given = data.get("length_m")
            if given is None:
                data = {**data, "length_m": total_m}
            elif not isinstance(given, (int, float)) or abs(given - total_m) > LENGTH_TOLERANCE_M:
                raise FieldPathError(
                    ("length_m",),
                    f"length_m={given!r} differs from the centreline's length {total_m:.2f} m by more than "
                    f"{LENGTH_TOLERANCE_M:g} m; omit length_m or make them agree",
                )
        return data

    @property
    def centreline_points_m(self) -> tuple[tuple[float, float], ...]:
        """The centreline's points (x_m, y_m): ``centreline_m``, or the straight [[0, 0], [length_m, 0]]."""
        if self.centreline_m is not None:
            return self.centreline_m
        return ((0.0, 0.0), (float(self.length_m), 0.0))
