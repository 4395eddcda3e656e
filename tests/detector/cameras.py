"""The camera the detector tests share."""

from __future__ import annotations

from detector.camera import CameraModel


def scene_b(**overrides) -> CameraModel:
    """The paper's scene B camera (Table 2): 3.1 m, 22 deg, 320 x 240, f 0.73 mm, 0.7 x 0.52 mm sensor."""
    params = dict(
        height_m=3.1,
        tilt_deg=22.0,
        focal_mm=0.73,
        sensor_w_mm=0.7,
        sensor_h_mm=0.52,
        width_px=320,
        height_px=240,
    )
    return CameraModel(**{**params, **overrides})
