"""Pinhole camera on a pole: intrinsics, pose, lens distortion, pixel <-> ground.

One model serves both the renderer (world -> pixel, with distortion, through
``cv2.projectPoints``) and the detector (pixel -> ground, undistorting only the
pixels it needs), so the two can never disagree about geometry.

Conventions (the world frame of docs/design/architecture.md):

* World frame: x along the street (m), y across it (m), z up (m); ground z = 0.
* The camera stands at ``(x_m, y_m, height_m)``; ``yaw_deg`` is the heading of
  its optical axis in the ground plane, counter-clockwise from +x;
  ``tilt_deg`` is the depression of the optical axis below the horizon
  (0 = horizontal, 90 = straight down); roll is 0.
* Camera frame is OpenCV's: x right, y down, z forward (optical axis).
* Pixel coordinates are OpenCV's continuous coordinates (u to the right, v
  down, pixel centres on integers); the principal point is the image centre
  ``(width_px / 2, height_px / 2)`` as in the paper's eq. 2.
* ``fx = focal_mm * width_px / sensor_w_mm``, ``fy = focal_mm * height_px / sensor_h_mm``.
* Distortion is OpenCV's (k1, k2, p1, p2, k3): the paper's eq. 1.
* "Distance" (the paper's d_o, eq. 4) is the *forward* ground distance: the
  distance from the pole foot to the ground point measured along the camera
  heading. For every pixel of one (undistorted) row it is the same number,
  ``height_m / tan(depression)``.
"""

from __future__ import annotations

import math
import types
import typing
from functools import cached_property
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from detector.cliargs import did_you_mean
from detector.yamlfile import read_yaml_mapping

#: A row whose depression below the horizon is at or below this, rad, has no ground point
#: (it looks at or above the horizon): every ground projection of the detector shares it.
MIN_DEPRESSION_RAD = 1e-9


class CameraError(ValueError):
    """A camera description that cannot be used; the message names the field or file."""


class NoGroundPointError(ValueError):
    """A pixel whose ray never meets the ground (at or above the horizon)."""


class CameraModel(BaseModel):
    """A calibrated camera on a pole. Immutable; all lengths in metres."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    height_m: float = Field(gt=0, le=100, description="lens height above the ground, m")
    tilt_deg: float = Field(ge=-30, lt=90, description="depression of the optical axis below the horizon, deg")
    focal_mm: float = Field(gt=0, le=100, description="focal length, mm")
    sensor_w_mm: float = Field(gt=0, le=100, description="sensor width, mm")
    sensor_h_mm: float = Field(gt=0, le=100, description="sensor height, mm")
    width_px: int = Field(ge=16, le=8192, description="image width, px")
    height_px: int = Field(ge=16, le=8192, description="image height, px")
    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    k3: float = 0.0
    x_m: float = Field(default=0.0, description="pole position along the street, m")
    y_m: float = Field(default=0.0, description="pole position across the street, m")
    yaw_deg: float = Field(default=0.0, description="heading of the optical axis, deg CCW from +x")
    fps: float = Field(default=15.0, gt=0, le=240, description="frame rate, frames/s")
    name: str = ""

    @model_validator(mode="after")
    def _must_see_ground(self) -> CameraModel:
        if self.bottom_row_depression_deg <= 0.0:
            raise ValueError(
                f"camera cannot see the ground: tilt_deg={self.tilt_deg} with a vertical "
                f"half field of view of {self.vertical_fov_deg / 2:.1f} deg puts the bottom "
                f"image row {-self.bottom_row_depression_deg:.1f} deg above the horizon; "
                f"valid tilt_deg > {-self.vertical_fov_deg / 2:.1f}"
            )
        return self

    # ------------------------------------------------------------------ loading
    @classmethod
    def from_yaml(cls, path: str | Path, **overrides: float) -> CameraModel:
        """Load a camera file; raise CameraError naming the file and the bad field."""
        data = read_yaml_mapping(path, "camera", CameraError)
        data.update(overrides)
        return cls.from_mapping(data, source=str(path))

    @classmethod
    def from_mapping(cls, data: dict, source: str = "camera") -> CameraModel:
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            raise CameraError(f"{source}: {format_validation_error(exc)}") from None

    def placed(self, **pose: float) -> CameraModel:
        """A copy at another pose (x_m, y_m, yaw_deg, height_m, tilt_deg ...)."""
        return self.model_validate({**self.model_dump(), **pose})

    # --------------------------------------------------------------- intrinsics
    @property
    def fx_px(self) -> float:
        return self.focal_mm * self.width_px / self.sensor_w_mm

    @property
    def fy_px(self) -> float:
        return self.focal_mm * self.height_px / self.sensor_h_mm

    @property
    def cx_px(self) -> float:
        return self.width_px / 2.0

    @property
    def cy_px(self) -> float:
        return self.height_px / 2.0

    @cached_property
    def intrinsic_matrix(self) -> np.ndarray:
        """K (3x3, pixels)."""
        return np.array(
            [[self.fx_px, 0.0, self.cx_px], [0.0, self.fy_px, self.cy_px], [0.0, 0.0, 1.0]]
        )

    @cached_property
    def distortion(self) -> np.ndarray:
        """OpenCV distortion vector (k1, k2, p1, p2, k3)."""
        return np.array([self.k1, self.k2, self.p1, self.p2, self.k3], dtype=np.float64)

    @cached_property
    def has_distortion(self) -> bool:
        return bool(np.any(self.distortion != 0.0))

    @property
    def vertical_fov_deg(self) -> float:
        return 2.0 * math.degrees(math.atan(self.sensor_h_mm / (2.0 * self.focal_mm)))

    @property
    def horizontal_fov_deg(self) -> float:
        return 2.0 * math.degrees(math.atan(self.sensor_w_mm / (2.0 * self.focal_mm)))

    @property
    def bottom_row_depression_deg(self) -> float:
        """Depression of the ray through the bottom image edge (undistorted), deg."""
        return self.tilt_deg + self.vertical_fov_deg / 2.0

    @property
    def horizon_row_px(self) -> float:
        """Undistorted image row of the horizon (may lie outside the image)."""
        return self.cy_px - self.fy_px * math.tan(math.radians(self.tilt_deg))

    # --------------------------------------------------------------------- pose
    @cached_property
    def rotation_world_to_cam(self) -> np.ndarray:
        """R with X_cam = R @ (X_world - C); rows are the camera's right, down, forward axes."""
        t, y = math.radians(self.tilt_deg), math.radians(self.yaw_deg)
        forward = np.array([math.cos(t) * math.cos(y), math.cos(t) * math.sin(y), -math.sin(t)])
        right = np.array([math.sin(y), -math.cos(y), 0.0])
        down = np.cross(forward, right)
        return np.stack([right, down, forward])

    @cached_property
    def position_m(self) -> np.ndarray:
        return np.array([self.x_m, self.y_m, self.height_m])

    @cached_property
    def rvec(self) -> np.ndarray:
        return cv2.Rodrigues(self.rotation_world_to_cam)[0]

    @cached_property
    def tvec(self) -> np.ndarray:
        return -self.rotation_world_to_cam @ self.position_m

    @property
    def heading_unit(self) -> np.ndarray:
        y = math.radians(self.yaw_deg)
        return np.array([math.cos(y), math.sin(y)])

    # ------------------------------------------------------------ world -> pixel
    def world_to_cam(self, points_world_m: np.ndarray) -> np.ndarray:
        """(N, 3) world points -> (N, 3) camera-frame points, m."""
        pts = np.asarray(points_world_m, dtype=np.float64).reshape(-1, 3)
        return (pts - self.position_m) @ self.rotation_world_to_cam.T

    def project(self, points_world_m: np.ndarray, distort: bool = True) -> np.ndarray:
        """(N, 3) world points -> (N, 2) pixels (distorted by default).

        Points behind the camera (z_cam <= 1 cm) come back as NaN.
        """
        cam = self.world_to_cam(points_world_m)
        out = np.full((len(cam), 2), np.nan)
        front = cam[:, 2] > 0.01
        if not np.any(front):
            return out
        if distort and self.has_distortion:
            px, _ = cv2.projectPoints(cam[front], np.zeros(3), np.zeros(3), self.intrinsic_matrix, self.distortion)
            out[front] = px.reshape(-1, 2)
        else:
            z = cam[front, 2]
            out[front, 0] = self.fx_px * cam[front, 0] / z + self.cx_px
            out[front, 1] = self.fy_px * cam[front, 1] / z + self.cy_px
        return out

    # ------------------------------------------------------------ pixel -> world
    def undistort_pixels(self, uv_px: np.ndarray) -> np.ndarray:
        """(N, 2) distorted pixels -> (N, 2) ideal pinhole pixels (paper eq. 1, inverted)."""
        uv = np.asarray(uv_px, dtype=np.float64).reshape(-1, 2)
        if not self.has_distortion or len(uv) == 0:
            return uv.copy()
        # the iterative variant with a tight criterion: the default 5 iterations leave
        # centimetre errors at the frame corners of strongly distorted cheap lenses
        und = cv2.undistortPointsIter(
            uv.reshape(-1, 1, 2), self.intrinsic_matrix, self.distortion, np.eye(3), self.intrinsic_matrix,
            (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10),
        )
        return und.reshape(-1, 2)

    def depression_rad(self, v_px: np.ndarray) -> np.ndarray:
        """Depression below the horizon of undistorted row(s) v: paper eqs. 2-3 (alpha), rad."""
        v = np.asarray(v_px, dtype=np.float64)
        return math.radians(self.tilt_deg) + np.arctan((v - self.cy_px) / self.fy_px)

    def forward_distance_m(self, v_px: np.ndarray) -> np.ndarray:
        """Forward ground distance of undistorted row(s) v: paper eq. 4, m.

        NaN where the row is at or above the horizon (no ground point) - never a
        negative or infinite distance.
        """
        alpha = np.asarray(self.depression_rad(v_px))
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.where(alpha > MIN_DEPRESSION_RAD, self.height_m / np.tan(np.maximum(alpha, MIN_DEPRESSION_RAD)), np.nan)
        return d

    def pixel_to_ground(self, uv_px: np.ndarray, undistorted: bool = False) -> np.ndarray:
        """(N, 2) pixels -> (N, 3) world ground points (z = 0), m. NaN rows: no ground point."""
        uv = np.asarray(uv_px, dtype=np.float64).reshape(-1, 2)
        if not undistorted:
            uv = self.undistort_pixels(uv)
        rays_cam = np.column_stack(
            [(uv[:, 0] - self.cx_px) / self.fx_px, (uv[:, 1] - self.cy_px) / self.fy_px, np.ones(len(uv))]
        )
        rays_world = rays_cam @ self.rotation_world_to_cam
        dz = rays_world[:, 2]
        out = np.full((len(uv), 3), np.nan)
        down = dz < -1e-12
        s = -self.height_m / dz[down]
        out[down] = self.position_m + rays_world[down] * s[:, None]
        out[down, 2] = 0.0
        return out

    def ground_point(self, u_px: float, v_px: float) -> np.ndarray:
        """One pixel -> its world ground point; raises NoGroundPointError above the horizon."""
        p = self.pixel_to_ground(np.array([[u_px, v_px]]))[0]
        if np.isnan(p[0]):
            raise NoGroundPointError(
                f"pixel (u={u_px:.1f}, v={v_px:.1f}) is at or above the horizon "
                f"(undistorted row {self.horizon_row_px:.1f}); it has no ground point"
            )
        return p

    def forward_and_lateral_m(self, points_world_m: np.ndarray) -> np.ndarray:
        """(N, 2|3) world points -> (N, 2) [forward, lateral-left] offsets from the pole foot, m."""
        pts = np.asarray(points_world_m, dtype=np.float64)
        rel = pts[:, :2] - self.position_m[:2]
        h = self.heading_unit
        return np.column_stack([rel @ h, rel @ np.array([-h[1], h[0]])])


def format_validation_error(exc: ValidationError, model: type[BaseModel] | None = None) -> str:
    """One line per bad field: dotted path, what was wrong, the value got.

    An unknown field is told the nearest valid names of the model at its place, found from
    ``model`` (the validated model class; default ``CameraModel`` for its own errors) or
    from a ``valid_fields`` list in the error's context.
    """
    if model is None and exc.title == CameraModel.__name__:
        model = CameraModel
    lines = []
    for err in exc.errors():
        loc = ".".join(str(p) for p in err["loc"]) or "(top level)"
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            valid = (err.get("ctx") or {}).get("valid_fields") or _field_names_at(model, tuple(err["loc"][:-1]))
            msg = "unknown field" + did_you_mean(str(err["loc"][-1]) if err["loc"] else "", valid)
        got = err.get("input")
        got_txt = "" if err["type"] in ("missing", "extra_forbidden") or isinstance(got, dict) else f" (got {got!r})"
        lines.append(f"{loc}: {msg}{got_txt}")
    return "; ".join(lines)


def _field_names_at(model: type[BaseModel] | None, path: tuple) -> list[str]:
    """The field names of the model(s) at ``path`` (a pydantic error location) below ``model``."""
    if model is None:
        return []
    nodes: list[Any] = [model]
    for key in path:
        below: list[Any] = []
        for node in (leaf for n in nodes for leaf in _leaf_types(n)):
            origin = typing.get_origin(node)
            if isinstance(node, type) and issubclass(node, BaseModel):
                if key in node.model_fields:
                    below.append(node.model_fields[key].annotation)
                elif key == node.__name__:  # pydantic tags a union member with its class name
                    below.append(node)
            elif origin in (tuple, list, set, frozenset) and isinstance(key, int):
                below.extend(a for a in typing.get_args(node) if a is not Ellipsis)
            elif origin is dict:
                below.append(typing.get_args(node)[1])
        nodes = below
    names: list[str] = []
    for node in (leaf for n in nodes for leaf in _leaf_types(n)):
        if isinstance(node, type) and issubclass(node, BaseModel):
            names.extend(f for f in node.model_fields if f not in names)
    return names


def _leaf_types(annotation: Any) -> list[Any]:
    """The alternatives of an Optional/Union/Annotated annotation (itself otherwise)."""
    origin = typing.get_origin(annotation)
    if origin in (typing.Union, types.UnionType):
        return [leaf for a in typing.get_args(annotation) for leaf in _leaf_types(a)]
    if origin is typing.Annotated:
        return _leaf_types(typing.get_args(annotation)[0])
    return [annotation]
