"""The probability that some street track is in a lamp's zone now or enters it within a lead time.

Per track: its position along the street now, s0 ~ N(mu0, sigma0^2), and after the lead, sL ~ N(muL,
sigmaL^2) (``kalman.predict``); a road user moving steadily sweeps [min(s0, sL), max(s0, sL)], which
meets zone [a, b) unless both lie before a or both at or after b. P(both < a) <= min(P(s0 < a),
P(sL < a)), so P(meets) >= 1 - min(...) - min(...): the bound used (it is exact when one of the
two is certain). Times the track's existence; zones combine their tracks as 1 - prod(1 - p).
Street s in metres; zones are [start, end) along s.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from scipy.special import ndtr

from citysim.control.fusion import kalman


def track_zone_probabilities(track, lead_s: float, zone_start_m: np.ndarray, zone_end_m: np.ndarray) -> np.ndarray:
    """(Z,) P(``track`` exists and is in or enters each zone within ``lead_s`` seconds)."""
    mu0, sigma0 = float(track.mean[0]), max(math.sqrt(float(track.cov[0, 0])), 1e-3)
    mean_l, cov_l = kalman.predict(track.mean, track.cov, lead_s, track.cls)
    mul, sigmal = float(mean_l[0]), max(math.sqrt(float(cov_l[0, 0])), 1e-3)
    before = np.minimum(ndtr((zone_start_m - mu0) / sigma0), ndtr((zone_start_m - mul) / sigmal))
    after = np.minimum(1.0 - ndtr((zone_end_m - mu0) / sigma0), 1.0 - ndtr((zone_end_m - mul) / sigmal))
    return track.existence * np.clip(1.0 - before - after, 0.0, 1.0)


def zone_probabilities(tracks: Sequence, lead_of: Callable[[str], float], zone_start_m: np.ndarray,
                       zone_end_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(Z,) P(some track is in or enters each zone within its class's lead, ``lead_of(cls)`` s), and
    (Z,) the index of the track that contributes most to each zone (-1: none)."""
    n = len(zone_start_m)
    if not tracks:
        return np.zeros(n), np.full(n, -1)
    per_track = np.array([track_zone_probabilities(t, lead_of(t.cls), zone_start_m, zone_end_m) for t in tracks])
    none = np.prod(1.0 - per_track, axis=0)
    best = np.where(per_track.max(axis=0) > 0.0, per_track.argmax(axis=0), -1)
    return 1.0 - none, best
