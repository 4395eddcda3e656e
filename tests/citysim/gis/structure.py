"""A structural check of an imported scenario against the real-street schema contract, without the
pydantic models (the branch that implements them is merged separately): the fields and rules the
contract states for centreline, poles and side entries."""

from __future__ import annotations

import math

from citysim.config.kinds import AGENT_KINDS

ENTRY_KINDS = {"junction", "path", "driveway"}


def _polyline_problems(points) -> list[str]:
    problems = []
    if len(points) < 2:
        problems.append("centreline_m needs >= 2 points")
    for a, b in zip(points, points[1:], strict=False):
        if math.dist(a, b) < 0.5:
            problems.append(f"centreline points {a} and {b} are < 0.5 m apart")
    return problems


def contract_problems(data: dict) -> list[str]:
    """What in scenario ``data`` breaks the contract (empty when nothing does)."""
    street, lamps = data["street"], data["lamps"]
    points = street["centreline_m"]
    problems = _polyline_problems(points)
    length = sum(math.dist(a, b) for a, b in zip(points, points[1:], strict=False))
    if abs(street.get("length_m", length) - length) > 0.5:
        problems.append(f"length_m {street['length_m']} differs from the centreline's {length:.2f} m")
    if not {"latitude_deg", "longitude_deg", "crs"} <= set(street["origin"]):
        problems.append("origin needs latitude_deg, longitude_deg, crs")
    s_values = [p["s_m"] for p in lamps["poles"]]
    if any(b - a < 1.0 for a, b in zip(s_values, s_values[1:], strict=False)):
        problems.append("poles must increase in s by >= 1 m")
    if any(not 0 <= s <= length for s in s_values) or any(not isinstance(p["d_m"], float) for p in lamps["poles"]):
        problems.append("poles must lie along the street with a d_m")
    totals: dict[str, float] = {}
    for e in street.get("side_entries", []):
        if e["side"] not in ("left", "right") or e["kind"] not in ENTRY_KINDS or not 0 < e["s_m"] < length:
            problems.append(f"bad side entry {e}")
        for cls, share in e["share"].items():
            if cls not in AGENT_KINDS:
                problems.append(f"side entry share names unknown class {cls!r}")
            totals[cls] = totals.get(cls, 0.0) + share
    problems += [f"shares of {cls} sum to {t:.3f} > 0.9" for cls, t in totals.items() if t > 0.9 + 1e-9]
    problems += [f"unknown traffic class {c!r}" for c in data["traffic"]["classes"] if c not in AGENT_KINDS]
    if "file" in lamps["camera"] or not {"focal_mm", "sensor_w_mm", "width_px"} <= set(lamps["camera"]):
        problems.append("the camera must be inline")
    return problems
