"""A street track's existence probability: raised by every detection, lowered by every camera that
should have seen it and did not (negative information); no timer.

Bayes on the odds: a detection associated with the track multiplies them by ``HIT_LIKELIHOOD_RATIO``
(how much likelier a detection there is when a road user stands there than from a false alarm);
a judged frame of a camera in whose view the track stands with probability ``visibility`` and
which reports nothing there multiplies them by ``1 - P_DETECT * visibility`` (the chance a real
road user is missed). A track nobody can see keeps its probability; only its position spreads.
"""

from __future__ import annotations

#: Chance that a judged frame of a camera reports a road user standing in its view (a hit of its
#: track): set below the detector's typical rate, so a real road user missed by a few frames is
#: not dropped, while a ghost seen once is gone within a few of the camera's frames.
P_DETECT = 0.25
#: ... per detector class where it differs: the detector loses cars for many frames at a time
#: (headlight glare toward the camera, a dark back going away) and bicycles often.
P_DETECT_BY_CLASS = {"vehicle": 0.05, "cyclist": 0.1}


def p_detect(cls: str) -> float:
    """The detection probability negative information assumes for a track of class ``cls``."""
    return P_DETECT_BY_CLASS.get(cls, P_DETECT)
#: Odds factor of one detection associated with a track.
HIT_LIKELIHOOD_RATIO = 3.0
#: Below this existence probability a track is dropped (it would light nothing at any sensible threshold).
P_DROP = 0.1
#: Existence never rises above this: however long a road user was seen, a dozen of a watching
#: camera's empty frames (under a second) can drop its track once it is gone.
P_MAX = 0.98


def after_hit(p: float, ratio: float = HIT_LIKELIHOOD_RATIO) -> float:
    """Existence probability ``p`` after one associated detection."""
    odds = p / max(1.0 - p, 1e-12) * ratio
    return min(odds / (1.0 + odds), P_MAX)


def after_miss(p: float, visibility: float, p_detect: float = P_DETECT) -> float:
    """Existence probability ``p`` after a judged frame of a camera that saw nothing of the track,
    which stood in its view with probability ``visibility`` (0..1)."""
    miss = 1.0 - p_detect * min(max(visibility, 0.0), 1.0)
    return p * miss / (1.0 - p + p * miss)
