"""Tracks as the detector's unit: each moving object followed across frames on the ground.

Owns the ground positions of regions (``ground``), one object's history and its pooled
class (``track``), the physical-plausibility rules that make a track noise (``plausibility``),
the association of a frame's regions with tracks (``associate``), the reunification of an
object's fragments (``reunite``) and the set of a camera's tracks (``tracker``). Plain Python
over a frame's handful of regions; it imports only the detector runtime.
"""
