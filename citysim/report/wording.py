"""Words the reports share for what a planner could misread: darkness, the oracle, the best controller.

The darkness figures (``citysim.metrics.zones``) count a zone as dark while its lamp is below the
level a road user needs, which is full level for every class: a lamp dimmed to its idle level or to
a schedule's 50 % is "dark" here though it is not off. The labels below say so.
"""

from __future__ import annotations

from collections.abc import Mapping

from citysim.report.runfacts import ZERO_SAVINGS
from citysim.sim.compare import ORACLE_SAVES_NOTHING_BELOW

__all__ = [
    "BELOW_FULL",
    "LIT_ENOUGH",
    "best_installable",
    "best_installable_sentence",
    "over_oracle_note",
    "oracle_saves_nothing",
]

#: What "dark" means in every darkness figure of a report.
BELOW_FULL = ("below full level (a lamp dimmed to its idle level or to a schedule's 50 % counts, "
              "though it is not off)")  # fmt: skip
#: The share of zone entries lit on entry a controller must reach to be called the best one (a saving
#: bought by leaving more than one entry in twenty below full is no recommendation).
LIT_ENOUGH = 0.95
#: Controllers that are yardsticks, not something to install: always_on lights everything, the oracle
#: knows where everyone is.
NOT_INSTALLABLE = ("always_on", "oracle")


def _kind(label: str, figures: Mapping) -> str:
    return str(figures.get("controller", label))


def best_installable(controllers: Mapping[str, Mapping], lit_share: float = LIT_ENOUGH) -> str | None:
    """The label of the installable controller (not always_on, not the oracle) saving most against
    always-on among those whose lit-on-entry rate is at least ``lit_share``; None when none qualifies
    or none saves anything.

    Parameters
    ----------
    controllers : mapping
        summary.json's ``controllers`` (label -> figures with ``savings_vs_always_on`` and
        ``lit_on_entry_rate``, both shares 0..1, and ``controller``, the registered kind).
    lit_share : float
        The least share of zone entries lit on entry, 0..1.

    Returns
    -------
    str or None
        The controller's label.
    """
    candidates = [(label, f) for label, f in controllers.items() if _kind(label, f) not in NOT_INSTALLABLE
                  and (f.get("lit_on_entry_rate") or 0.0) >= lit_share
                  and (f.get("savings_vs_always_on") or 0.0) >= ZERO_SAVINGS]  # fmt: skip
    if not candidates:
        return None
    return max(candidates, key=lambda lf: lf[1]["savings_vs_always_on"])[0]


def best_installable_sentence(controllers: Mapping[str, Mapping], lit_share: float = LIT_ENOUGH) -> str:
    """One sentence naming ``best_installable`` with its saving and lit-on-entry rate, and the rule."""
    rule = (f"the installable controllers (not always_on or the oracle) that light at least {100 * lit_share:.0f} % "
            "of zone entries on entry")
    name = best_installable(controllers, lit_share)
    if name is None:
        return f"None of {rule} saves energy."
    f = controllers[name]
    return (f"Best controller: {name}, saving {100 * f['savings_vs_always_on']:.1f} % against always-on with "
            f"{100 * f['lit_on_entry_rate']:.1f} % of zone entries lit on entry; the most saving of {rule}.")


def over_oracle_note(controllers: Mapping[str, Mapping]) -> str | None:
    """The footnote a savings-vs-oracle column needs when some controller saves more than the oracle
    (a share above 100 %); None when none does.

    Parameters
    ----------
    controllers : mapping
        summary.json's ``controllers`` (label -> figures with ``savings_vs_oracle``, a share, and
        ``lit_on_entry_rate``, 0..1).

    Returns
    -------
    str or None
        The sentence, naming each such controller with its lit-on-entry rate.
    """
    above = [(label, f) for label, f in controllers.items() if (f.get("savings_vs_oracle") or 0.0) > 1.0]
    if not above:
        return None
    who = ", ".join(f"{label} ({100 * f['savings_vs_oracle']:.0f} %, lit on entry "
                    f"{100 * (f.get('lit_on_entry_rate') or 0.0):.1f} %)" for label, f in above)  # fmt: skip
    return (f"vs oracle above 100 %: {who}. The oracle lights every zone entry at full with the least energy "
            "a sensing lamp needs for it, so a saving beyond it is bought by leaving road users below full level "
            "(see lit on entry) or, for a clock schedule, by paying no sensing power: it is not a better "
            "controller.")


def oracle_saves_nothing(controllers: Mapping[str, Mapping]) -> str | None:
    """The note replacing a savings-vs-oracle column whose bound saves nothing (the oracle's own
    saving against always-on below ``ORACLE_SAVES_NOTHING_BELOW``, where summary.json's
    ``savings_vs_oracle`` is None: its lamps at full nearly the whole run, as on a short or busy
    run), where a share of it would read as nonsense; None when the bound saves (or the run has no
    oracle)."""
    oracle = next((f for label, f in controllers.items() if _kind(label, f) == "oracle"), None)
    saving = None if oracle is None else oracle.get("savings_vs_always_on")
    if saving is None or saving >= ORACLE_SAVES_NOTHING_BELOW:
        return None
    why = ("its sensing power outweighs its dimming" if saving < ZERO_SAVINGS
           else "its lamps were at full nearly the whole run")  # fmt: skip
    return (f"vs oracle not given: the oracle saves {100 * saving:.1f} % against always-on on this run, less "
            f"than {100 * ORACLE_SAVES_NOTHING_BELOW:g} % ({why}), so there is no saving to take a share of.")
