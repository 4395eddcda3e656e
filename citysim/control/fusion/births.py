"""Where a road user can appear: a new street track's prior existence by where it is first seen.

A road user comes into a camera's view from a street end, from a side entry, or out of a stretch
no camera sees; anywhere else it was already seen by some camera and should have a track. So a
detection nobody's track explains is most likely a real newcomer within ``ENTRY_M`` of where
coverage begins (``P_BIRTH_ENTRY``), and most likely a false alarm in the middle of a watched
stretch (``P_BIRTH_INSIDE``: it needs repeated evidence). Coverage is sampled along the street's
centreline, each lane and each sidewalk (street s, d; m).
"""

from __future__ import annotations

import numpy as np

from citysim.control.fusion.views import CameraViews

#: How far inside covered ground from its edge a newcomer is first seen, m (a walker's 3.5 s, a car's third of a second).
ENTRY_M = 5.0
#: Prior existence of a track born where a road user can appear, and of one born elsewhere.
P_BIRTH_ENTRY = 0.6
P_BIRTH_INSIDE = 0.15
#: Coverage is sampled this finely along the street, m.
STEP_M = 0.5


class BirthMap:
    """Per stretch of street: whether a road user can first be seen there.

    Parameters
    ----------
    views : CameraViews
        The street's cameras' views.
    length_m : float
        The street's length, m.
    lateral_m : sequence of float
        The d offsets (m) sampled across the street (lanes' and sidewalks' centres).
    side_entries_s_m : sequence of float
        s (m) of side entries (side streets, paths) along the street, if any.
    """

    def __init__(self, views: CameraViews, length_m: float, lateral_m, side_entries_s_m=()):
        self.s_m = np.arange(STEP_M / 2, length_m, STEP_M)
        covered = np.zeros(len(self.s_m), dtype=bool)
        for d_m in lateral_m:
            xy = np.array([views.frame.to_ground(s, d_m) for s in self.s_m])
            covered |= views.seen_xy(xy).any(axis=1)
        # distance along s from each sample to the nearest uncovered ground (off the street counts)
        edges = np.concatenate([[-STEP_M / 2], self.s_m[~covered], [length_m + STEP_M / 2]])
        gap_m = np.abs(self.s_m[:, None] - edges[None, :]).min(axis=1)
        entry = gap_m <= ENTRY_M
        for s_entry in side_entries_s_m:
            entry |= np.abs(self.s_m - s_entry) <= ENTRY_M
        self.entry = entry
        self.covered = covered

    def prior(self, s_m: float) -> float:
        """Prior existence of a track first seen at ``s_m`` (m along the street)."""
        i = int(np.clip(np.searchsorted(self.s_m, s_m), 0, len(self.s_m) - 1))
        return P_BIRTH_ENTRY if self.entry[i] else P_BIRTH_INSIDE
