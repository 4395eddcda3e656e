"""Which measurement of one camera frame belongs to which street track.

First the detector's own links: a measurement whose detector track (camera, track id) already
fed a street track goes to it when it lies within ``LINK_GATE`` (a loose gate: the detector kept
the identity). The rest are assigned by the Hungarian method (``scipy.optimize.linear_sum_assignment``)
on the squared Mahalanobis distance, gated at ``GATE`` (chi-square, 2 degrees of freedom, 99 %):
this is the hand-over, a measurement of another camera found where a track is predicted to be.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from citysim.control.fusion.kalman import mahalanobis2

#: Squared Mahalanobis gate of a new association: the chi-square 99 % point with 2 degrees of freedom.
GATE = 9.21
#: Gate of a measurement whose detector track already fed the street track (chi-square 2 dof, 99.99 %).
LINK_GATE = 18.4
_FAR = 1e9


def associate(tracks: Sequence, measurements: Sequence, links: dict) -> dict[int, int]:
    """``{measurement index: track index}`` for one camera frame.

    ``tracks`` have ``mean``, ``cov`` and ``id`` (predicted to the frame's time); ``measurements``
    are ``Measurement``s; ``links`` maps a detector track key to the street track id it fed.
    """
    pairs: dict[int, int] = {}
    index_of = {t.id: i for i, t in enumerate(tracks)}
    taken: set[int] = set()
    for m_i, m in enumerate(measurements):
        t_i = index_of.get(links.get(m.key)) if m.key is not None else None
        if t_i is None or t_i in taken:
            continue
        if mahalanobis2(tracks[t_i].mean, tracks[t_i].cov, m.z, m.cov_m2) <= LINK_GATE:
            pairs[m_i] = t_i
            taken.add(t_i)
    rest_m = [i for i in range(len(measurements)) if i not in pairs]
    rest_t = [i for i in range(len(tracks)) if i not in taken]
    if not rest_m or not rest_t:
        return pairs
    cost = np.full((len(rest_m), len(rest_t)), _FAR)
    for a, m_i in enumerate(rest_m):
        m = measurements[m_i]
        for b, t_i in enumerate(rest_t):
            track = tracks[t_i]
            if abs(track.mean[0] - m.s_m) > 40.0:  # far apart along the street: not worth the algebra
                continue
            d2 = mahalanobis2(track.mean, track.cov, m.z, m.cov_m2)
            if d2 <= GATE:
                cost[a, b] = d2
    rows, cols = linear_sum_assignment(cost)
    for a, b in zip(rows.tolist(), cols.tolist(), strict=True):
        if cost[a, b] < _FAR:
            pairs[rest_m[a]] = rest_t[b]
    return pairs
