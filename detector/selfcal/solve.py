"""A camera's height and tilt from walkers' head and foot rows (roll 0, intrinsics known).

Geometry (``detector.camera``'s convention: ``tilt_deg`` is the depression of the optical
axis below the horizon; image rows v grow downwards; principal point at the image centre): the
ray through row v has depression ``alpha(v) = tilt + arctan((v - cy) / fy)`` and meets
everything at forward distance d at height ``H - d tan(alpha)``. A person of height h whose
feet stand at forward distance d has foot row v_f and head row v_h with

    tan(alpha_h) / tan(alpha_f) = (H - h) / H,   so   c = h / H = 1 - tan(alpha_h) / tan(alpha_f).

A walker keeps his height as he walks nearer or farther: the tilt is the one that makes c
constant along every walker's track (the head line and the foot line of a walker meet at the
horizon; a wrong tilt bends one of them). Scale needs one length: the walkers' mean height is
the prior (Table 1's pedestrians, 1.15-2.0 m: mean 1.575 m), so ``H = mean h / mean c``.
Tracks moving faster than ``MAX_WALK_MPS`` on the ground (cyclists, cars) or whose height is
far from the prior are dropped and the estimate repeated. Uncertainties are the standard
deviation over bootstrap resamples of the walkers (seeded: the same numbers every run).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from detector.classes import TABLE1

#: the prior height of a walker, m: the middle of Table 1's pedestrian heights
PRIOR_HEIGHT_M = sum(TABLE1["pedestrian"].height_m) / 2
#: faster than this on the ground is no walker, m/s (Table 1's cyclists ride 3-8 m/s)
MAX_WALK_MPS = 2.6
#: the tilts searched, deg
TILT_RANGE_DEG = (-10.0, 75.0)
BOOTSTRAP_RESAMPLES = 40
#: how far beyond the bottom row's point (the nearer toe) the top row's point (the crown's far
#: edge) lies along the ground, m: the nearer toe is on average about 0.2 m in front of the body's
#: axis (half the feet's spread in a step plus half a foot) and the crown's far edge about 0.1 m
#: behind it (half a head); measured on citysim's walkers at 8-12 m: 0.23 m and 0.10 m
BOX_DEPTH_M = 0.3
#: a sighting whose box is shorter than this is left out, px: the segmenter loses the faint top
#: and bottom pixel rows of a small walker (measured against citysim's truth boxes: 1-2 px of
#: 12-25 px tall boxes, none of 40 px and more), which makes far walkers look shorter
MIN_BOX_PX = 20.0
#: a track needs this many sightings of at least ``MIN_BOX_PX`` to count
MIN_SIGHTINGS = 8
#: a track whose feet move fewer rows than this constrains no tilt, px
MIN_FOOT_RANGE_PX = 10.0


class CalibrationError(ValueError):
    """Too few walkers, or none that fits one camera; the message says what footage would do."""


@dataclass(frozen=True)
class Calibration:
    """The estimate: height m and tilt deg with their standard deviations, and what it rests on."""

    height_m: float
    height_sd_m: float
    tilt_deg: float
    tilt_sd_deg: float
    walkers: int
    sightings: int
    prior_height_m: float


def _log_c(tilt_rad: float, tracks: list[np.ndarray], cy_px: float, fy_px: float,
           head_shift_px: float = 0.0, offset_ratio: float = 0.0) -> list[np.ndarray] | None:
    """log(h / H) of every sighting of every track at this tilt (``head_shift_px``: with every
    head row moved down by that much; ``offset_ratio``: ``BOX_DEPTH_M`` / H, the top row's point
    that far beyond the bottom row's); None where a foot row would be at or above the horizon
    (no ground point)."""
    out = []
    for t in tracks:
        tan_h = np.tan(tilt_rad + np.arctan((t[:, 2] + head_shift_px - cy_px) / fy_px))
        a_f = tilt_rad + np.arctan((t[:, 3] - cy_px) / fy_px)
        if (a_f <= 1e-3).any() or (a_f >= math.pi / 2).any():
            return None
        # a sighting with no height left (a region cut or merged) is held at 1/1000 of H: the robust
        # cost caps its weight
        out.append(np.log(np.maximum(1.0 - tan_h / np.tan(a_f) - tan_h * offset_ratio, 1e-3)))
    return out


#: a sighting's residual is capped at this many pixels (a region cut or merged for a frame), px
MAX_RESIDUAL_PX = 3.0


def _cost(tilt_deg: float, tracks: list[np.ndarray], cy_px: float, fy_px: float, offset_ratio: float = 0.0) -> float:
    """Mean squared spread of log(h/H) about each track's own median, in head-row pixels (each
    sighting's deviation divided by how much a pixel moves its log(h/H) at this tilt, so the
    segmentation's pixel noise weighs the same at every tilt): least at the tilt under which
    walkers keep their height as they come nearer or go farther. Robust: a deviation counts at
    most ``MAX_RESIDUAL_PX``. ``offset_ratio``: ``BOX_DEPTH_M`` / H (``_log_c``)."""
    tilt = math.radians(tilt_deg)
    logs = _log_c(tilt, tracks, cy_px, fy_px, offset_ratio=offset_ratio)
    shifted = _log_c(tilt, tracks, cy_px, fy_px, head_shift_px=1.0, offset_ratio=offset_ratio)
    if logs is None or shifted is None:
        return math.inf
    total = n = 0.0
    for lc, lc1 in zip(logs, shifted, strict=True):
        per_px = np.maximum(np.abs(lc1 - lc), 1e-9)
        dev = np.minimum(np.abs(lc - np.median(lc)) / per_px, MAX_RESIDUAL_PX)
        total += float(dev @ dev)
        n += len(lc)
    return total / n


def fit_tilt_deg(tracks: list[np.ndarray], cy_px: float, fy_px: float, near_deg: float | None = None,
                 offset_ratio: float = 0.0) -> float:
    """The tilt that keeps every track's h/H most constant, deg: a grid over ``TILT_RANGE_DEG``
    (or +-3 deg around ``near_deg``) refined by a bounded scalar search (``offset_ratio``: ``_log_c``)."""
    lo, hi = TILT_RANGE_DEG if near_deg is None else (near_deg - 3.0, near_deg + 3.0)
    grid = np.arange(lo, hi + 1e-9, 0.5)
    costs = [_cost(t, tracks, cy_px, fy_px, offset_ratio) for t in grid]
    best = float(grid[int(np.argmin(costs))])
    res = minimize_scalar(_cost, bounds=(best - 0.5, best + 0.5), args=(tracks, cy_px, fy_px, offset_ratio),
                          method="bounded", options={"xatol": 1e-3})
    return float(res.x) if res.fun <= min(costs) else best


def _height_m(tilt_deg: float, tracks: list[np.ndarray], cy_px: float, fy_px: float, prior_m: float,
              offset_ratio: float = 0.0) -> tuple[float, np.ndarray]:
    """(camera height m, each track's c = h / H) at this tilt."""
    logs = _log_c(math.radians(tilt_deg), tracks, cy_px, fy_px, offset_ratio=offset_ratio)
    if logs is None:
        raise CalibrationError("the walkers' feet are above the horizon at the tilt found: a clip with people "
                               "walking towards or away from the camera, wholly in view")
    c = np.array([math.exp(float(np.median(lc))) for lc in logs])
    # the median walker: a minority of tracks of body parts (legs not segmented) reads too tall
    return prior_m / float(np.median(c)), c


def _fit(tracks: list[np.ndarray], cy_px: float, fy_px: float, prior_m: float,
         near_deg: float | None = None) -> tuple[float, float, np.ndarray]:
    """(tilt deg, height m, each track's h/H): the tilt first with the box depth left out, then
    twice more with ``BOX_DEPTH_M`` / H at the height just found (it changes H by a few per cent)."""
    tilt = fit_tilt_deg(tracks, cy_px, fy_px, near_deg)
    height, c = _height_m(tilt, tracks, cy_px, fy_px, prior_m)
    for _ in range(2):
        ratio = BOX_DEPTH_M / height
        tilt = fit_tilt_deg(tracks, cy_px, fy_px, tilt, ratio)
        height, c = _height_m(tilt, tracks, cy_px, fy_px, prior_m, ratio)
    return tilt, height, c


def _ground_speed_mps(track: np.ndarray, height_m: float, tilt_deg: float, cx_px: float, fx_px: float,
                      cy_px: float, fy_px: float, fps: float) -> float:
    """Median ground speed of a track's feet, m/s (forward distance and lateral offset from the foot rows)."""
    tilt = math.radians(tilt_deg)
    a_f = tilt + np.arctan((track[:, 3] - cy_px) / fy_px)
    forward = height_m / np.tan(a_f)
    along_axis = forward * math.cos(tilt) + height_m * math.sin(tilt)  # depth in the camera frame
    lateral = (track[:, 1] - cx_px) * along_axis / fx_px
    steps = np.hypot(np.diff(forward), np.diff(lateral)) / (np.diff(track[:, 0]) / fps)
    return float(np.median(steps)) if len(steps) else 0.0


def calibrate(tracks: list[np.ndarray], width_px: int, height_px: int, fx_px: float, fy_px: float, fps: float,
              *, prior_height_m: float = PRIOR_HEIGHT_M, min_walkers: int = 3) -> Calibration:
    """Estimate height and tilt from upright image tracks (``detector.selfcal.walkers``) of a camera
    with focal lengths ``fx_px``/``fy_px`` (principal point at the image centre, no distortion).

    Raises CalibrationError with fewer than ``min_walkers`` walkers left after the checks.
    """
    cx, cy = width_px / 2.0, height_px / 2.0
    tall = [t[t[:, 3] - t[:, 2] >= MIN_BOX_PX] for t in tracks]
    # a walker must change his distance: a track whose foot row hardly moves constrains no tilt
    kept = [t for t in tall if len(t) >= MIN_SIGHTINGS and np.ptp(t[:, 3]) >= MIN_FOOT_RANGE_PX]
    if len(kept) < min_walkers:
        raise CalibrationError(f"only {len(kept)} walkers moved nearer or farther in view (at least {min_walkers} "
                               "needed): a longer clip, with people walking towards or away from the camera")
    tilt, height, c = _fit(kept, cy, fy_px, prior_height_m)
    for _ in range(2):  # drop what is no walker, then fit again
        speeds = [_ground_speed_mps(t, height, tilt, cx, fx_px, cy, fy_px, fps) for t in kept]
        heights = c * height
        lo, hi = 0.7 * prior_height_m, 1.4 * prior_height_m
        walkers = [t for t, s, h in zip(kept, speeds, heights, strict=True) if s <= MAX_WALK_MPS and lo <= h <= hi]
        if len(walkers) < min_walkers:
            raise CalibrationError(f"only {len(walkers)} of {len(kept)} tracks walk like people (at least "
                                   f"{min_walkers} needed): a longer clip, with people walking towards or away "
                                   "from the camera")
        if len(walkers) == len(kept):
            break
        kept = walkers
        tilt, height, c = _fit(kept, cy, fy_px, prior_height_m, near_deg=tilt)
    rng = np.random.default_rng(0)
    samples = []
    for _ in range(BOOTSTRAP_RESAMPLES):
        resample = [kept[i] for i in rng.integers(0, len(kept), len(kept))]
        t_b, h_b, _ = _fit(resample, cy, fy_px, prior_height_m, near_deg=tilt)
        samples.append((h_b, t_b))
    sd_h, sd_t = np.std(np.array(samples), axis=0)
    return Calibration(height_m=height, height_sd_m=float(sd_h), tilt_deg=tilt, tilt_sd_deg=float(sd_t),
                       walkers=len(kept), sightings=int(sum(len(t) for t in kept)), prior_height_m=prior_height_m)
