"""A tiny city for the city tests: three short streets of the year tests' toy, two controllers."""

from __future__ import annotations

from pathlib import Path

import yaml

from tests.citysim.year.conftest import toy_mapping

#: (name, street length m, lamps, pedestrians an hour): three streets, busier as they grow.
STREETS = (("elm", 80, 2, 600), ("oak", 120, 3, 900), ("ash", 160, 4, 1200))
#: The city's costs: no price change, so a payback is capex / yearly net saving (hand-checkable).
COSTS = {"energy_price_per_kwh": 0.3, "energy_price_change_per_year": 0.0, "discount_rate": 0.05,
         "lifetime_years": 10, "pir_sensor_per_pole": 50.0, "controller_node_per_pole": 100.0,
         "installation_per_pole": 50.0, "pir_maintenance_per_pole_year": 2.0,
         "controller_maintenance_per_pole_year": 3.0}  # fmt: skip
SITE = {"latitude_deg": 51.2, "longitude_deg": 6.8, "timezone": "Europe/Berlin", "year": 2025}


def street_mapping(name: str, length_m: float, lamps: int, pedestrians_per_hour: float) -> dict:
    m = toy_mapping()
    m["name"] = name
    m["street"]["length_m"] = length_m
    m["lamps"]["count"] = lamps
    m["traffic"]["classes"]["pedestrian"]["rate_per_hour"] = pedestrians_per_hour
    m["traffic"]["classes"]["vehicle"]["rate_per_hour"] = 240
    # the street's own site and costs, which the city's replace
    m["year"].update(latitude_deg=10.0, longitude_deg=10.0, timezone="Africa/Lagos")
    m["costs"] = {"energy_price_per_kwh": 9.0}
    return m


def write_city(folder: Path, **city) -> Path:
    """Three street files and CITY.yaml listing them (relative paths) in ``folder``; the city file's path."""
    folder.mkdir(parents=True, exist_ok=True)
    for street in STREETS:
        (folder / f"{street[0]}.yaml").write_text(yaml.safe_dump(street_mapping(*street)))
    data = {"name": "toytown", "streets": [f"{s[0]}.yaml" for s in STREETS], "site": SITE, "costs": COSTS, **city}
    path = folder / "city.yaml"
    path.write_text(yaml.safe_dump(data))
    return path
