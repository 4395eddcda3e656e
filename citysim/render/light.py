"""Radiometry of the simulated near-infrared camera: how bright a surface looks.

Every renderer module computes *linear radiance* ``L`` in sensor full-scale
units (``L = 1`` saturates the pixel) and only the last step turns it into
8-bit numbers with the camera response ``DN = 255 * sqrt(clip(L, 0, 1))``
(a gamma of 1/2, as cheap cameras compress their range; ``sqrt`` is the
fastest such curve in OpenCV).

``L = reflectance * (E_emitter + E_day + E_lamps + E_night)`` where, for a
surface at distance ``r_m`` from the lens:

* ``E_emitter = (1 - ambient) * P * cos_incidence * beam(off_axis) / r_m**2``:
  the IR emitter sits at the lens, so incidence is the angle between the
  viewing ray and the surface normal, and the LED beam falls off as
  ``cos(off_axis)**2``. In daylight the auto-exposure turns the gain down so
  far that the emitter stops mattering, hence the ``(1 - ambient)`` factor.
* ``E_day = ambient * DAY_IRRADIANCE * (up-facing 1, vertical VERTICAL_DAY_FACTOR)``.
* ``E_lamps``: each street lamp at ``level`` (0..1) is a point source at its
  luminaire with a street-light ("batwing") distribution: intensity
  ``LAMP_POWER / cos(theta)**2`` from the nadir out to ``LAMP_SPREAD_DEG``,
  which makes the road's illuminance fall only as ``cos(theta)`` (a broad,
  even pool, as street lighting is designed to give), then cut off toward the
  horizontal: ``E = level * I(theta) * cos_surface / d**2``.
* ``E_night``: sky glow, so unlit surfaces are not pitch black.

Conventions: world frame of docs/design/architecture.md (m), unit normals, distances in metres.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numba import njit, vectorize

#: Irradiance x m^2 of a street lamp at level 1 (full-scale units): under a
#: 6 m pole a 0.25-reflectance road reads about 95 DN (a walker beside it ~190 DN).
LAMP_POWER = 20.0
#: Daylight irradiance on an up-facing surface (full-scale units).
DAY_IRRADIANCE = 1.0
#: Vertical surfaces get sky light and some sun, less than the ground.
VERTICAL_DAY_FACTOR = 0.6
#: Sky glow at night (full-scale units), so unlit surfaces stay just above black.
NIGHT_IRRADIANCE = 0.004
#: Radiance of the sky itself at night and in daylight.
SKY_NIGHT = 0.003
SKY_DAY = 0.55
#: Angle from the nadir out to which the luminaire's intensity grows as 1/cos^2.
LAMP_SPREAD_DEG = 65.0
#: Cosine below which a lamp's light fades out toward the horizontal (full cut-off luminaire).
LAMP_CUTOFF_COS = 0.15
#: Emitter beam falls off as cos(off-axis angle) ** BEAM_EXPONENT.
BEAM_EXPONENT = 2.0


SPREAD_COS = float(np.cos(np.radians(LAMP_SPREAD_DEG)))


def emitter_irradiance(
    emitter_power: float,
    ambient_light: float,
    r_m: np.ndarray,
    cos_incidence: np.ndarray,
    cos_off_axis: np.ndarray,
) -> np.ndarray:
    """IR emitter irradiance at surfaces ``r_m`` from the lens (full-scale units)."""
    r2 = np.maximum(np.asarray(r_m, dtype=np.float64) ** 2, 0.04)
    beam = np.clip(cos_off_axis, 0.0, 1.0) ** BEAM_EXPONENT
    return (1.0 - ambient_light) * emitter_power * np.abs(cos_incidence) * beam / r2


def day_irradiance(ambient_light: float, normal_z: np.ndarray) -> np.ndarray:
    """Daylight on a surface with unit normal z-component ``normal_z`` (1 = facing up)."""
    nz = np.clip(np.asarray(normal_z, dtype=np.float64), 0.0, 1.0)
    return ambient_light * DAY_IRRADIANCE * (VERTICAL_DAY_FACTOR + (1.0 - VERTICAL_DAY_FACTOR) * nz)


def night_irradiance(ambient_light: float) -> float:
    """Sky glow, fading out as daylight takes over."""
    return (1.0 - ambient_light) * NIGHT_IRRADIANCE


def sky_radiance(ambient_light: float) -> float:
    return SKY_NIGHT + ambient_light * (SKY_DAY - SKY_NIGHT)


@njit(cache=True, nogil=True)
def lamp_light(vx, vy, vz, nx, ny, nz, upright):  # pragma: no cover - compiled
    """Irradiance from a street lamp at level 1 at a surface point, ``(vx, vy, vz)`` m from
    the point to the luminaire; the surface's unit normal ``(nx, ny, nz)``, or ``upright``
    for a small upright body (person, car), which catches light about as well from every
    side: its cosine is taken as 0.5 plus half the lamp's elevation seen from the point.
    The one statement of the lamps' light: the background (``lamp_irradiance``) and the
    agents (``citysim.render.kernels.pose_parts``) both use it."""
    d2 = max(vx * vx + vy * vy + vz * vz, 0.25)
    d = math.sqrt(d2)
    cos_nadir = vz / d  # angle from the lamp's downward axis
    fade = min(max(cos_nadir * (1.0 / LAMP_CUTOFF_COS), 0.0), 1.0)
    spread = max(cos_nadir, SPREAD_COS)
    fade /= spread * spread
    if upright:
        cos_surface = 0.5 + 0.5 * max(cos_nadir, 0.0)
    else:
        cos_surface = min(max((vx * nx + vy * ny + vz * nz) / d, 0.0), 1.0)
    return LAMP_POWER * fade * cos_surface / d2


@vectorize(
    ["float64(float64, float64, float64, float64, float64, float64, boolean)"],
    cache=True,
    nopython=True,
)
def _lamp_light_ufunc(vx, vy, vz, nx, ny, nz, upright):  # pragma: no cover - compiled
    return lamp_light(vx, vy, vz, nx, ny, nz, upright)


def lamp_irradiance(
    points_m: np.ndarray, normals: np.ndarray | None, lamp_positions_m: np.ndarray
) -> np.ndarray:
    """(N, 3) surface points -> (N, L) irradiance from L lamps at level 1 (``lamp_light``).

    ``normals`` (N, 3) unit vectors, or None for small upright bodies.
    Occlusion (shadows) is not modelled.
    """
    pts = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    lamps = np.asarray(lamp_positions_m, dtype=np.float64).reshape(-1, 3)
    v = lamps[None, :, :] - pts[:, None, :]
    if normals is None:
        n = np.zeros((len(pts), 1, 3))
    else:
        n = np.asarray(normals, dtype=np.float64).reshape(-1, 1, 3)
    return _lamp_light_ufunc(
        v[..., 0], v[..., 1], v[..., 2], n[..., 0], n[..., 1], n[..., 2], normals is None
    )


def radiance_to_dn(radiance: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Linear radiance (float32, full scale 1) -> 8-bit camera output, DN = 255 sqrt(L).

    Radiance is a sum of non-negative terms; a rounding-level negative gives
    sqrt = NaN, which the saturating conversion turns into 0, as it should.
    """
    return cv2.convertScaleAbs(cv2.sqrt(radiance), dst=out, alpha=255.0)
