"""The street before the lamp chain's end zones: where road users come from.

Road users come onto the simulated street at its ends (x = 0 m and x = ``length_m``, going +x
and -x). Where an end lamp's zone reaches the street's end, they appear inside that zone: no
controller can bring the lamp to full before they enter it, not even the oracle (which knows
every road user on the street, and none before it is there). Each of them meets a lamp still
ramping up, every controller's lit-on-entry rate is capped below 100 %, and the oracle is no
longer the bound at zero darkness its savings are compared with (seen on rural_road before it
had approaches: the oracle lit 83 % of entries on entry).

A planner's street goes on beyond the chain (other streets' lamps light it), so a scenario
gives each end an *approach*: street before the first zone and after the last, at least as
long as the fastest road user covers while the oracle brings a lamp from dim to full.
"""

from __future__ import annotations

from dataclasses import dataclass

from citysim.config.motion import MAX_SPEED_MPS
from citysim.config.scenario import Scenario


@dataclass(frozen=True)
class Approaches:
    """The street before the first lamp zone and after the last (m), and the least each needs."""

    first_m: float  # from x = 0 to the first zone's start
    last_m: float  # from the last zone's end to x = length_m
    needed_m: float

    @property
    def short_ends(self) -> list[str]:
        """'start' and/or 'end': the street ends whose approach is shorter than needed."""
        return [name for name, m in (("start", self.first_m), ("end", self.last_m)) if m < self.needed_m]

    def as_dict(self) -> dict:
        return {"first_m": round(self.first_m, 2), "last_m": round(self.last_m, 2),
                "needed_m": round(self.needed_m, 2), "short_ends": self.short_ends}  # fmt: skip


def oracle_lead_s(luminaire, physics_step_s: float) -> float:
    """How long before a target enters a zone the oracle (``citysim.control.oracle``) brings its lamp
    to full: the dim-to-full part of ``ramp_up_s`` plus two of the world's steps (it decides once a
    step), s. Here, not in the oracle, because the approach a street needs is measured by it and the
    world may not import the controllers; ``luminaire`` a ``LuminaireSpec``."""
    return (1.0 - luminaire.dim_level) * luminaire.ramp_up_s + 2.0 * physics_step_s


def approach_needed_m(scenario: Scenario) -> float:
    """How far the fastest road user (60 km/h) goes in the oracle's lead (``oracle_lead_s``), m."""
    return MAX_SPEED_MPS * oracle_lead_s(scenario.lamps.luminaire, 1.0 / scenario.physics_hz)


def approaches(scenario: Scenario) -> Approaches:
    """The scenario's approaches (x along the street, m; zones from ``LampsSpec.zones``)."""
    length_m = scenario.street.length_m
    zones = scenario.lamps.zones(length_m)
    return Approaches(first_m=zones[0][0], last_m=length_m - zones[-1][1], needed_m=approach_needed_m(scenario))


def describe_short(found: dict) -> str | None:
    """One line for people when an end has no approach (``Approaches.as_dict``), else None."""
    short = found.get("short_ends") or []
    if not short:
        return None
    where = " and ".join(f"the street's {end} ({found['first_m' if end == 'start' else 'last_m']:.0f} m)"
                         for end in short)  # fmt: skip
    return (f"note: the end lamp zones reach {where}: road users appear inside them, so no controller, "
            f"not even the oracle, lights them before they enter; give each end an approach of at least "
            f"{found['needed_m']:.1f} m (street.length_m, lamps.first_x_m) for lit-on-entry figures that "
            f"mean what they say")
