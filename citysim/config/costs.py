"""Scenario schema for the money: what sensing lamps cost to buy, fit and keep, and what a kWh costs.

One optional section, ``costs:``, of a scenario (every field has a default, so a scenario without
it is costed with the defaults below). Amounts are in the ``year`` section's currency (EUR by
default) and per pole: a controller kind's hardware is bought once for every lamp of the street.
Each default names the published figure it is taken from in its field description; they are the
order of a German municipal retrofit in 2024, not a quote. ``citysim.year.money`` turns them into
capex, yearly opex, payback years and net present value against always-on lamps.

Which hardware a controller needs (``citysim.year.money.HARDWARE``): a camera controller a camera
node and a controller node, ``pir`` a PIR sensor and a controller node, ``schedule`` a controller
node, ``always_on`` nothing.
"""

from __future__ import annotations

from pydantic import Field

from citysim.config.base import Spec

#: Used for ``energy_price_per_kwh`` when neither the costs nor the year section give a price.
DEFAULT_ENERGY_PRICE_PER_KWH = 0.25
#: Used for ``grid_kg_co2_per_kwh`` when neither the costs nor the year section give a factor.
DEFAULT_GRID_KG_CO2_PER_KWH = 0.38


class CostsSpec(Spec):
    """Hardware, installation and upkeep per pole and controller kind; lifetime, discounting, energy price."""

    camera_node_per_pole: float = Field(
        default=180.0, ge=0, le=1e5,
        description="camera node per pole, currency: a single-board computer, a NoIR camera module, an "
        "850 nm IR emitter, a weatherproof housing and power supply (default 180: Raspberry Pi 4 list "
        "price ~55 + Camera Module 3 NoIR ~25 + IR illuminator ~20 + IP66 enclosure and PSU ~80, EUR)",
    )  # fmt: skip
    pir_sensor_per_pole: float = Field(
        default=60.0, ge=0, le=1e5,
        description="pole-mounted outdoor PIR motion sensor per pole, currency (default 60: the price "
        "range of street-light PIR sensors in luminaire makers' 2024 catalogues, 40-80 EUR)",
    )  # fmt: skip
    controller_node_per_pole: float = Field(
        default=90.0, ge=0, le=1e5,
        description="radio/controller node per pole that dims the driver and talks to neighbours "
        "(Zhaga-D4i or NEMA socket node), currency (default 90: 60-120 EUR per node in published "
        "municipal smart-lighting business cases, e.g. the EU Smart Cities Marketplace street-lighting "
        "guidance)",
    )  # fmt: skip
    installation_per_pole: float = Field(
        default=80.0, ge=0, le=1e5,
        description="fitting the hardware to one pole (bucket truck, two fitters, commissioning), "
        "currency; counted once per pole for every controller that needs hardware (default 80: "
        "German municipal retrofit tenders price 50-120 EUR per luminaire)",
    )  # fmt: skip
    camera_maintenance_per_pole_year: float = Field(
        default=12.0, ge=0, le=1e4,
        description="upkeep of a camera node per pole and year (lens cleaning, SD card and IR emitter "
        "replacement, software updates), currency (default 12: assumed as ~7 % of the node's price a "
        "year, the upper end of the 2-7 % a year usual for electronics in lighting business cases)",
    )  # fmt: skip
    pir_maintenance_per_pole_year: float = Field(
        default=3.0, ge=0, le=1e4,
        description="upkeep of a PIR sensor per pole and year, currency (default 3: ~5 % of its price)",
    )
    controller_maintenance_per_pole_year: float = Field(
        default=6.0, ge=0, le=1e4,
        description="upkeep of a controller node per pole and year (radio network, central management "
        "licence), currency (default 6: the per-node yearly fee range of 3-10 EUR quoted in municipal "
        "CMS business cases)",
    )  # fmt: skip
    lifetime_years: int = Field(
        default=10, ge=1, le=50,
        description="years the sensing hardware is used before it is replaced; NPV and CO2 avoided are "
        "summed over it (default 10: the service life usually assumed for luminaire electronics, shorter "
        "than an LED luminaire's 20+ years)",
    )  # fmt: skip
    discount_rate: float = Field(
        default=0.03, ge=0, le=0.5,
        description="yearly discount rate of the NPV, a fraction (default 0.03: the social discount rate "
        "the European Commission's Better Regulation Toolbox, tool 61, recommends)",
    )  # fmt: skip
    energy_price_per_kwh: float | None = Field(
        default=None, ge=0, le=100,
        description="energy price in the first year, currency per kWh (default: the year section's "
        "tariff_per_kwh when it is above 0, else 0.25, the order of German municipal street-lighting "
        "contracts in 2024 from BDEW's electricity price analysis for non-household customers)",
    )  # fmt: skip
    energy_price_change_per_year: float = Field(
        default=0.02, ge=-0.5, le=1.0,
        description="yearly change of the energy price, a fraction (default 0.02: the ECB's 2 % inflation "
        "target, i.e. a constant real price)",
    )  # fmt: skip
    grid_kg_co2_per_kwh: float | None = Field(
        default=None, ge=0, le=5,
        description="grid emission factor for the CO2 avoided, kg CO2 per kWh (default: the year section's "
        "grid_kg_co2_per_kwh when above 0, else 0.38, Umweltbundesamt's 2023 figure for the German mix)",
    )  # fmt: skip

    def price_per_kwh(self, tariff_per_kwh: float = 0.0) -> float:
        """The first year's energy price: this section's, else ``tariff_per_kwh`` if > 0, else the default."""
        if self.energy_price_per_kwh is not None:
            return self.energy_price_per_kwh
        return tariff_per_kwh if tariff_per_kwh > 0 else DEFAULT_ENERGY_PRICE_PER_KWH

    def kg_co2_per_kwh(self, grid_kg_co2_per_kwh: float = 0.0) -> float:
        """The emission factor: this section's, else ``grid_kg_co2_per_kwh`` if > 0, else the default."""
        if self.grid_kg_co2_per_kwh is not None:
            return self.grid_kg_co2_per_kwh
        return grid_kg_co2_per_kwh if grid_kg_co2_per_kwh > 0 else DEFAULT_GRID_KG_CO2_PER_KWH
