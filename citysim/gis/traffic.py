"""Traffic defaults by highway class: assumed night-time arrivals per hour of each road-user class.

These are guesses of the order of a German residential street on a weeknight from 22:00 (the
reference scenario suburban_night's figures for residential), scaled by how busy each class of
street usually is. They are not counts: replace them with your street's (edit the written file,
give --rate CLASS=PER_HOUR, or give `citysim year` your counter's hourly counts).
"""

from __future__ import annotations

from citysim.config.motion import MAX_SPEED_KMH

#: Arrivals per hour at 22:00 by highway class and road-user class.
RATES_PER_HOUR = {
    "residential": {"pedestrian": 36, "group": 6, "cyclist": 5, "vehicle": 18, "animal": 1.5, "e_scooter": 6},
    "living_street": {"pedestrian": 30, "group": 6, "cyclist": 4, "vehicle": 4, "animal": 1.5, "e_scooter": 3},
    "unclassified": {"pedestrian": 20, "group": 3, "cyclist": 6, "vehicle": 40, "animal": 1.5, "e_scooter": 4},
    "tertiary": {"pedestrian": 40, "group": 8, "cyclist": 12, "vehicle": 120, "animal": 1.0, "e_scooter": 8},
    "secondary": {"pedestrian": 40, "group": 8, "cyclist": 15, "vehicle": 300, "animal": 0.5, "e_scooter": 8},
    "service": {"pedestrian": 10, "group": 2, "cyclist": 2, "vehicle": 4, "animal": 1.5, "e_scooter": 1},
}
#: Highway classes not listed above use these.
DEFAULT_CLASS = "residential"
#: Share of the 22:00 rate in each hour from 22:00 (suburban_night's weeknight profiles).
HOURLY_PROFILE = {
    "pedestrian": [1.0, 0.7, 0.4, 0.2, 0.1, 0.1, 0.2, 0.6],
    "group": [1.0, 0.8, 0.4, 0.2, 0.1, 0.1, 0.1, 0.3],
    "cyclist": [1.0, 0.6, 0.3, 0.2, 0.1, 0.2, 0.5, 1.0],
    "vehicle": [1.0, 0.7, 0.4, 0.2, 0.15, 0.2, 0.6, 1.2],
    "e_scooter": [1.0, 0.6, 0.3, 0.2, 0.1, 0.2, 0.5, 1.0],
}


def vehicle_speed_kmh(limit_kmh: float) -> dict[str, float]:
    """Vehicle speeds for a speed limit (km/h): normal around 90 % of it, from 60 % to 110 %,
    capped at the simulator's top speed."""
    top = min(limit_kmh * 1.1, MAX_SPEED_KMH)
    low = round(min(limit_kmh * 0.6, top), 1)
    mean = round(min(limit_kmh * 0.9, top), 1)
    return {"min": low, "max": round(top, 1), "mean": mean, "std": round(max(limit_kmh * 0.1, 0.5), 1)}


def traffic_classes(highway: str, limit_kmh: float, rates: dict[str, float] | None = None) -> dict:
    """The scenario's traffic.classes mapping for a street of ``highway`` class.

    Parameters
    ----------
    highway : the OSM highway class (unknown classes use residential's rates).
    limit_kmh : the speed limit, km/h (sets the vehicles' speeds).
    rates : per-class arrivals per hour that replace the defaults.
    """
    table = dict(RATES_PER_HOUR.get(highway, RATES_PER_HOUR[DEFAULT_CLASS]))
    table.update(rates or {})
    classes: dict[str, dict] = {}
    for cls, rate in table.items():
        entry: dict = {"rate_per_hour": float(rate)}
        if cls in HOURLY_PROFILE:
            entry["hourly_profile"] = HOURLY_PROFILE[cls]
        if cls == "vehicle":
            entry["speed_kmh"] = vehicle_speed_kmh(limit_kmh)
        classes[cls] = entry
    return classes
