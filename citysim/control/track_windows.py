"""k of n frames per track: the windows ``detector_confirmed`` (and its kin) confirm targets by.

The paper's implementation switches a lamp on when 2 of the last 6 frames hold a target (eq. 12),
one window for the whole frame, so an insect at the emitter in one frame and a flicker in another
add up to a confirmation. Here the window is kept per track of the detector (``TrackWindows``):
a frame is a hit of its track when its own class is a target or its track is one, unless a
physics rule says no road user moves as the track does (``frame_hit``); a track is confirmed
once it has been seen in n frames, by when an insect's track has shown itself 'jumping' or 'too
fast' (from its second and fifth sighting); a young track standing on an established one is a
fragment of it and counts for it (``fragment_keys``: a car passing close to the camera breaks
into pieces that live a few frames each). Keys are track ids; None is the one window of
detections without a track (the per-frame path).
"""

from __future__ import annotations

import math

from detector.tracks.tracker import STILL_REASON

#: the paper's implementation switches when 2 of the last 6 frames hold a target (eq. 12)
PAPER_K, PAPER_N = 2, 6
#: the plausibility reasons (``detector.tracks.plausibility``) that say no road user moves so:
#: insects at the emitter, rain, swaying branches. A track given one loses the hits of its
#: window; reasons that only say "not yet known" or "not a Table 1 shape" do not.
NOT_A_ROAD_USER = frozenset({"too fast", "erratic", "jumping", "size unsteady", "oscillating in place"})


def frame_hit(d, threshold: float) -> bool | None:
    """What detection ``d`` adds to its track's k-of-n window this frame (``detector_confirmed`` per
    track): True (a hit) when its track is a target or the frame's own P(target) reaches
    ``threshold``, None when a physics rule says no road user moves as its track does, else False.
    A track whose velocity is not yet known counts by its frames, so an approaching car lights its
    lamp about as soon as the frame-by-frame detector would; the track must first be seen in n
    frames (``TrackWindows``), by when an insect's track has shown itself 'jumping' or 'too fast'.
    A still region of a tracking detector (a camera looking steeply down: ground a car uncovered,
    ``detector.ghosts``; track_id None, reason ``STILL_REASON``) is never a hit, whatever its own
    P(target): the key None it would count under is no track, and its frames would add up there."""
    if d.track_id is None:
        if d.track_reason == STILL_REASON:  # a still region (a steep camera's ghost): no road user
            return False
    elif d.track_reason in NOT_A_ROAD_USER:
        return None
    return bool(d.track_target) or d.p_target >= threshold


#: a young track's detection standing this near an established track's on the ground is a
#: fragment of that road user (a car passing close to the camera breaks into pieces that live a
#: few frames each), m: about a car's length
FRAGMENT_M = 4.5


def plausible_marks(detections, threshold: float, keys: list | None = None) -> dict:
    """``{track key: hit?}`` of one frame for ``TrackWindows.update`` (None: ruled out), by
    ``frame_hit``; ``keys``: each detection's key (default its track id; see ``fragment_keys``)."""
    marks: dict = {}
    for d, key in zip(detections, keys or [d.track_id for d in detections], strict=True):
        if marks.get(key, False) is not None:
            hit = frame_hit(d, threshold)
            marks[key] = None if hit is None else marks.get(key, False) or hit
    return marks


def keyed_marks(detections, threshold: float, window: TrackWindows) -> tuple[list, dict]:
    """Each detection's window key (``fragment_keys``) and the frame's marks by those keys
    (``plausible_marks``), before ``window.update``."""
    keys = fragment_keys(detections, window)
    return keys, plausible_marks(detections, threshold, keys)


def fragment_keys(detections, window: TrackWindows) -> list:
    """Each detection's window key: its track id, or, for a track not yet seen enough (``window``)
    standing within ``FRAGMENT_M`` of an established plausible track's detection on the ground,
    the nearest such track's id (a fragment counts for the road user it belongs to)."""
    keys = [d.track_id for d in detections]
    if not window.min_seen:  # every track is seen enough: none is a fragment (fast mode's windows)
        return keys
    anchors = [(d.ground_x_m, d.ground_y_m, d.track_id) for d in detections
               if d.track_id is not None and d.ground_x_m is not None and window.seen_enough(d.track_id)
               and d.track_reason not in NOT_A_ROAD_USER]  # fmt: skip
    if not anchors:
        return keys
    for i, d in enumerate(detections):
        if d.track_id is None or d.ground_x_m is None or window.seen_enough(d.track_id):
            continue
        dist_m, key = min((math.hypot(d.ground_x_m - x, d.ground_y_m - y), k) for x, y, k in anchors)
        if dist_m <= FRAGMENT_M:
            keys[i] = key
    return keys


class TrackWindows:
    """The last n target decisions of each track of one camera; a track is confirmed at k hits.

    Keys are track ids (None: detections without a track, which share one window). A frame in
    which a track is not seen counts as a miss; a window with no hit left is forgotten, so the
    state stays as small as the tracks in view. With ``full_window`` a track is confirmed only once
    it has been seen in n frames: by then the physics rules that need its ground velocity have
    spoken (an insect at the emitter is 'jumping' or 'too fast' by its fifth sighting).
    """

    def __init__(self, k: int, n: int, full_window: bool = False) -> None:
        self.k, self.n, self.mask = k, n, (1 << n) - 1
        self.min_seen = n if full_window else 0
        self.bits: dict = {}
        self.seen: dict = {}  # key -> (frames it was seen in, frames since it was last seen)

    def update(self, hits: dict) -> set:
        """Record one frame's ``{track key: target?}`` (None: ruled out this frame, no road user
        moves so: the track loses its hits); return the confirmed keys."""
        if not hits and not self.bits and not self.seen:  # nothing in view, nothing remembered
            return set()
        mask = self.mask
        bits = {key: b for key, b in ((key, (b << 1) & mask) for key, b in self.bits.items()) if b}
        for key, hit in hits.items():
            if hit is None:
                bits.pop(key, None)
            elif hit:
                bits[key] = bits.get(key, 0) | 1
        self.bits = bits
        k = self.k
        if not self.min_seen:
            return {key for key, b in bits.items() if b.bit_count() >= k}
        # a key is remembered while it holds hits or was seen in its last n frames
        n = self.n
        seen = {key: (count + (key in hits), 0 if key in hits else unseen + 1)
                for key, (count, unseen) in self.seen.items() if key in hits or key in bits or unseen + 1 < n}  # fmt: skip
        for key in hits:
            seen.setdefault(key, (1, 0))
        self.seen = seen
        return {key for key, b in bits.items() if b.bit_count() >= k and self.seen_enough(key)}

    def seen_enough(self, key) -> bool:
        """Whether track ``key`` has been seen in enough frames to be confirmed (always without
        ``full_window``; detections without a track share one window, always seen enough)."""
        return not self.min_seen or key is None or self.seen.get(key, (0, 0))[0] >= self.min_seen


def windows_wait(sensors) -> bool:
    """Whether a controller's per-track windows must wait for n sightings themselves: yes for the
    real detector; no for fast mode's drawn detections (``ctx.sensors.drawn``), whose calibrated
    tables already leave out the hits of tracks not yet seen enough (``citysim.fast.records``)."""
    return not getattr(sensors, "drawn", False)
