"""Negative information: what a camera's empty frame says of a track it should have seen.

A judged frame of a camera that reports nothing where a track may stand tells two things: the
track is less likely to exist, and, if it exists, it is less likely to stand in the stretch
[a, b] (street s, m) the camera sees. With the track's position along the street N(mu, sigma^2)
and detection probability Pd, the posterior is N(s) (1 - Pd 1[a <= s <= b]) up to a constant:
its mass (``1 - Pd * visibility``) scales the existence odds, and its mean and variance
(moments of a normal truncated to [a, b], in closed form) move the track out of the seen stretch.
That move is applied as a Kalman update of the position with a pseudo-measurement of s; the
speeds are left alone (a walker not yet seen where predicted is taken to be further back, not
slower: taking it slower, measured on the tests' walkers, parked lost tracks at a view's edge).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr

_SQRT_2PI = math.sqrt(2.0 * math.pi)
_H_S = np.array([[1.0, 0.0, 0.0, 0.0]])


def _pdf(z: float) -> float:
    return math.exp(-0.5 * z * z) / _SQRT_2PI


def missed_moments(mu: float, sigma: float, a: float, b: float, p_detect: float) -> tuple[float, float, float]:
    """(mass, mean, variance) of N(mu, sigma^2) times (1 - p_detect on [a, b]); mass = 1 - p_detect * P(a <= s <= b)."""
    alpha, beta = (a - mu) / sigma, (b - mu) / sigma
    z = float(ndtr(beta) - ndtr(alpha))
    pa, pb = _pdf(alpha), _pdf(beta)
    e1 = mu * z + sigma * (pa - pb)  # E[s 1[a, b]]
    e2 = sigma * sigma * (z + alpha * pa - beta * pb) + 2.0 * mu * sigma * (pa - pb) + mu * mu * z  # E[s^2 1[a, b]]
    mass = 1.0 - p_detect * z
    mean = (mu - p_detect * e1) / mass
    var = (mu * mu + sigma * sigma - p_detect * e2) / mass - mean * mean
    return mass, mean, max(var, 1e-9)


def missed(mean: np.ndarray, cov: np.ndarray, a: float, b: float, p_detect: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The state after a camera seeing [a, b] (s, m) with detection probability ``p_detect`` saw
    nothing of the track; and the visibility-weighted miss factor for its existence (the mass)."""
    mu, sigma = float(mean[0]), math.sqrt(max(float(cov[0, 0]), 1e-12))
    mass, mu_post, var_post = missed_moments(mu, sigma, a, b, p_detect)
    prior_info, post_info = 1.0 / (sigma * sigma), 1.0 / var_post
    if post_info <= prior_info * (1.0 + 1e-6):  # the seen stretch splits the belief: no Gaussian sharpening
        return mean, cov, mass
    r = 1.0 / (post_info - prior_info)
    z = r * (mu_post * post_info - mu * prior_info)
    y = np.array([z - mu])
    s = _H_S @ cov @ _H_S.T + r
    gain = cov @ _H_S.T / s
    gain[2:] = 0.0  # the position only: a road user's pace is its own, whatever a camera failed to see
    ikh = np.eye(4) - gain @ _H_S
    return mean + (gain @ y), ikh @ cov @ ikh.T + gain @ gain.T * r, mass
