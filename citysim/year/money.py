"""The planner's money: capex, opex, payback years, NPV and CO2 avoided of each controller against always-on.

Every figure compares a controller with always-on lamps on the same street and year, for the
``n`` poles of the street, with the scenario's ``costs`` section (``citysim.config.costs``):

* ``capex = n x (sum of the controller's hardware per pole + installation per pole)``; 0 for a
  controller that needs no hardware (``HARDWARE`` says which devices each controller needs);
* ``opex_per_year = n x (sum of the devices' maintenance per pole and year)``;
* ``S = E_always_on - E`` is the energy saved in a year, kWh (from the year's table);
* ``money_saved_per_year = S x p - opex_per_year``: the first year's net saving at the first
  year's energy price ``p``;
* the energy price changes by ``g`` (``energy_price_change_per_year``) a year, so year ``t``
  (1 = first) saves ``N_t = S x p x (1 + g)^(t - 1) - opex_per_year``; maintenance stays flat;
* ``npv = -capex + sum_{t=1..L} N_t / (1 + r)^t`` with ``L`` = ``lifetime_years`` and ``r`` =
  ``discount_rate``: cash flows at the end of each year, discounted to the day of installation;
* ``payback_years``: the (undiscounted) years until ``N_1 + N_2 + ...`` reaches capex, linear
  within the year it is reached (``capex / N_1`` when ``g = 0``); 0 without capex; None if it
  is not reached within ``MAX_PAYBACK_YEARS`` (the saving never covers the outlay);
* ``co2_avoided_kg_over_lifetime = S x c x L`` with ``c`` the grid's kg CO2 per kWh.

Two controllers are no investment, and get None (null in year.json) where a figure does not apply:
always-on is the reference (capex, upkeep, saving, NPV and CO2 avoided 0; no payback: None); a
bound (``BOUNDS``: the oracle, and the oracle on what the cameras see) is not something one can
install (no hardware: capex, opex, payback and NPV None; ``money_saved_per_year = S x p`` and the
CO2 avoided are the most any controller could save, before upkeep).
"""

from __future__ import annotations

from dataclasses import dataclass

from citysim.config.costs import CostsSpec

#: Beyond this many years a payback is reported as never (None).
MAX_PAYBACK_YEARS = 100

#: Per device: (its price per pole, its maintenance per pole and year): field names of CostsSpec.
DEVICES = {
    "camera_node": ("camera_node_per_pole", "camera_maintenance_per_pole_year"),
    "pir_sensor": ("pir_sensor_per_pole", "pir_maintenance_per_pole_year"),
    "controller_node": ("controller_node_per_pole", "controller_maintenance_per_pole_year"),
}
#: The devices each controller needs per pole (by controller name); a camera controller not named
#: here needs ``CAMERA_HARDWARE``.
HARDWARE = {
    "always_on": (),
    "schedule": ("controller_node",),
    "pir": ("pir_sensor", "controller_node"),
}
CAMERA_HARDWARE = ("camera_node", "controller_node")
#: The reference every figure is measured against: no investment, so no payback.
REFERENCE = "always_on"
#: Bounds, not products (they know where road users are): no hardware to buy or keep, so no capex,
#: opex, payback or NPV.
BOUNDS = ("oracle", "oracle_seen")


def hardware_of(name: str) -> tuple[str, ...]:
    """The devices (``DEVICES`` keys) per pole that controller ``name`` needs (none for a bound)."""
    from citysim.control.registry import CONTROLLERS

    if name in HARDWARE:
        return HARDWARE[name]
    if name in BOUNDS:
        return ()
    cls = CONTROLLERS.get(name)
    return CAMERA_HARDWARE if cls is None or cls.uses_camera else ("controller_node",)


@dataclass(frozen=True)
class Prices:
    """What one kWh costs in the first year and emits, and how the price and money change over time."""

    price_per_kwh: float
    kg_co2_per_kwh: float
    price_change_per_year: float
    discount_rate: float
    lifetime_years: int


def prices_of(costs: CostsSpec, tariff_per_kwh: float = 0.0, grid_kg_co2_per_kwh: float = 0.0) -> Prices:
    """The prices of ``costs``, falling back to the year section's tariff and grid factor (then defaults)."""
    return Prices(costs.price_per_kwh(tariff_per_kwh), costs.kg_co2_per_kwh(grid_kg_co2_per_kwh),
                  costs.energy_price_change_per_year, costs.discount_rate, costs.lifetime_years)  # fmt: skip


def capex_opex(costs: CostsSpec, devices: tuple[str, ...], poles: int) -> tuple[float, float]:
    """(capex, opex per year) of ``devices`` on ``poles`` poles, currency; installation once per pole."""
    if not devices:
        return 0.0, 0.0
    per_pole = sum(getattr(costs, DEVICES[d][0]) for d in devices) + costs.installation_per_pole
    upkeep = sum(getattr(costs, DEVICES[d][1]) for d in devices)
    return poles * per_pole, poles * upkeep


def net_saving(saved_kwh: float, opex_per_year: float, prices: Prices, t: int) -> float:
    """Year ``t``'s (1 = first) net saving: energy saved at that year's price minus maintenance."""
    return saved_kwh * prices.price_per_kwh * (1.0 + prices.price_change_per_year) ** (t - 1) - opex_per_year


def npv(capex: float, saved_kwh: float, opex_per_year: float, prices: Prices) -> float:
    """Net present value over the lifetime: ``-capex + sum_t N_t / (1 + r)^t`` (see the module docstring)."""
    return -capex + sum(net_saving(saved_kwh, opex_per_year, prices, t) / (1.0 + prices.discount_rate) ** t
                        for t in range(1, prices.lifetime_years + 1))  # fmt: skip


def payback_years(capex: float, saved_kwh: float, opex_per_year: float, prices: Prices) -> float | None:
    """Undiscounted years until the net savings add up to capex (linear within the year); None if never."""
    if capex <= 0:
        return 0.0
    total = 0.0
    for t in range(1, MAX_PAYBACK_YEARS + 1):
        gain = net_saving(saved_kwh, opex_per_year, prices, t)
        if gain > 0 and total + gain >= capex:
            return (t - 1) + (capex - total) / gain
        total += gain
    return None


def money_figures(kwh_per_year: dict[str, float], names: dict[str, str], poles: int, costs: CostsSpec,
                  prices: Prices) -> dict[str, dict]:  # fmt: skip
    """Per controller label: capex, opex_per_year, money_saved_per_year, payback_years, npv and
    co2_avoided_kg_over_lifetime against always-on; None where a figure does not apply (always-on's
    payback; a bound's capex, opex, payback and NPV: the module docstring).

    Parameters
    ----------
    kwh_per_year : each controller label's energy in the year, kWh (must hold ``always_on``)
    names : each label's controller name (what ``HARDWARE`` is looked up by)
    poles : lamps (poles) on the street, each fitted with the controller's hardware
    costs : the scenario's costs section
    prices : first-year price, emission factor, price change, discount rate and lifetime
    """
    reference_kwh = kwh_per_year["always_on"]
    out = {}
    for label, kwh in kwh_per_year.items():
        name = names.get(label, label)
        capex, opex = capex_opex(costs, hardware_of(name), poles)
        saved = reference_kwh - kwh
        out[label] = {
            "capex": capex,
            "opex_per_year": opex,
            "money_saved_per_year": net_saving(saved, opex, prices, 1),
            "payback_years": None if name == REFERENCE else payback_years(capex, saved, opex, prices),
            "npv": npv(capex, saved, opex, prices),
            "co2_avoided_kg_over_lifetime": saved * prices.kg_co2_per_kwh * prices.lifetime_years,
        }
        if name in BOUNDS:  # nothing to buy: only what it saves applies
            out[label].update(capex=None, opex_per_year=None, payback_years=None, npv=None)
    return out


def add_money(controllers: dict[str, dict], scenario, year, names: list[str] | None) -> dict:
    """Add ``money_figures`` to each controller's annual figures (year.json's ``controllers``, in
    place) for ``scenario``'s poles and costs; return the prices and counts they were computed with."""
    from citysim.sim.compare import resolve_controllers

    prices = prices_of(scenario.costs, year.tariff_per_kwh, year.grid_kg_co2_per_kwh)
    poles = len(scenario.lamps.positions_x_m)
    labels = {s.display_name: s.name for s in resolve_controllers(scenario, names)}
    kwh = {label: f["energy_kwh_per_year"] for label, f in controllers.items()}
    for label, money in money_figures(kwh, labels, poles, scenario.costs, prices).items():
        controllers[label].update(money)
    return {"poles": poles, **vars(prices), "costs": scenario.costs.model_dump(mode="json")}
