"""A constant-velocity Kalman filter in street coordinates, written here in numpy.

State ``[s, d, v_s, v_d]``: position along the street and across it (m) and their speeds
(m/s); measurements are ground positions ``[s, d]`` with their own 2x2 covariance (m^2, from
the camera model: ``citysim.control.fusion.measurement``). Process noise is white acceleration,
discretised exactly (so predicting in two steps equals predicting in one), its standard
deviation per axis and road-user class (``ACCEL_SD_MPS2``).

Why our own and not filterpy's ``KalmanFilter``: the model is four states and two lines of
algebra; filterpy is not maintained since 2018 and would be a dependency for ~40 lines, and here
predict and update are plain functions of arrays (a track is a mean and a covariance), which the
tracker copies and compares freely.
"""

from __future__ import annotations

import numpy as np

#: White-acceleration standard deviation (along the street, across it), m/s^2, per detector class:
#: walkers mostly keep their pace and their sidewalk, cars brake and accelerate along their lane but keep it
#: (a walker's position along the street is then known to 1.6 m after 8.6 s unseen, the 12 m under a pole).
ACCEL_SD_MPS2 = {"pedestrian": (0.1, 0.1), "group": (0.1, 0.1), "cyclist": (0.5, 0.1), "vehicle": (1.5, 0.1)}
DEFAULT_ACCEL_SD_MPS2 = (0.8, 0.3)
#: Measurement matrix: the filter is told positions (s, d).
H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])


def transition(dt_s: float) -> np.ndarray:
    """F of the constant-velocity model over ``dt_s`` seconds (4x4)."""
    f = np.eye(4)
    f[0, 2] = f[1, 3] = dt_s
    return f


def process_noise(dt_s: float, accel_sd_mps2: tuple[float, float]) -> np.ndarray:
    """Q over ``dt_s`` seconds for white acceleration of ``accel_sd_mps2`` (along, across; m/s^2)."""
    q = np.zeros((4, 4))
    dt2, dt3 = dt_s * dt_s / 2.0, dt_s**3 / 3.0
    for pos, vel, sd in ((0, 2, accel_sd_mps2[0]), (1, 3, accel_sd_mps2[1])):
        var = sd * sd
        q[pos, pos], q[pos, vel], q[vel, pos], q[vel, vel] = dt3 * var, dt2 * var, dt2 * var, dt_s * var
    return q


def predict(mean: np.ndarray, cov: np.ndarray, dt_s: float, cls: str) -> tuple[np.ndarray, np.ndarray]:
    """The state ``dt_s`` seconds later (dt_s >= 0) for a road user of detector class ``cls``."""
    if dt_s <= 0.0:
        return mean, cov
    f = transition(dt_s)
    return f @ mean, f @ cov @ f.T + process_noise(dt_s, ACCEL_SD_MPS2.get(cls, DEFAULT_ACCEL_SD_MPS2))


def innovation(mean: np.ndarray, cov: np.ndarray, z: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Innovation y = z - H x (m) and its covariance S = H P H' + R (m^2) of measurement ``z`` (s, d)."""
    return z - H @ mean, H @ cov @ H.T + r


def mahalanobis2(mean: np.ndarray, cov: np.ndarray, z: np.ndarray, r: np.ndarray) -> float:
    """Squared Mahalanobis distance of measurement ``z`` (its covariance ``r``) from the predicted
    position: chi-square with 2 degrees of freedom when ``z`` is this track's."""
    y, s = innovation(mean, cov, z, r)
    return float(y @ np.linalg.solve(s, y))


def update(mean: np.ndarray, cov: np.ndarray, z: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The state after measuring position ``z`` (s, d; m) with covariance ``r`` (m^2), Joseph form."""
    y, s = innovation(mean, cov, z, r)
    gain = np.linalg.solve(s, H @ cov).T  # P H' S^-1 (S and P symmetric)
    ikh = np.eye(4) - gain @ H
    return mean + gain @ y, ikh @ cov @ ikh.T + gain @ r @ gain.T
