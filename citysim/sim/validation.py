"""Fast mode against full fidelity: the same nights run both ways, figure by figure.

``validate`` runs the scenario's controllers in full fidelity and in fast mode on validation
seeds (the scenario's seed and the next ones; never calibration's, see
``citysim.sim.calibration``) and compares four figures per controller, pooled over the seeds:

=====================  ===============================  ==========================================
figure                 pooled over seeds as             agrees when |fast - full| is within
=====================  ===============================  ==========================================
savings                mean of savings_vs_always_on     2 percentage points
lit_on_entry_rate      mean                             1 percentage point
lag p95                mean of each night's lag_p95_s   0.5 s
false on-time          sum of false_on_time_s           10 % of the full figure (at least 1 s)
=====================  ===============================  ==========================================

Both sides see the same traffic (a seed fixes it; the controller never changes it), so the
differences are the sensor model's, not the traffic's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from citysim.config.scenario import Scenario, override
from citysim.sim.calibration import CALIBRATION_SEED_BASE, calibration_nights, sensor_model_for
from citysim.sim.compare import run_comparison
from citysim.sim.loop import RunError

DEFAULT_DURATION_S = 120.0
DEFAULT_SEEDS = 2


@dataclass(frozen=True)
class Figure:
    """One compared figure: its summary key, how it is pooled and its tolerance."""

    key: str
    label: str
    pooled: str  # "mean" or "sum"
    tolerance: float
    relative: bool = False
    floor: float = 0.0

    def allowed(self, full: float) -> float:
        return max(self.tolerance * abs(full), self.floor) if self.relative else self.tolerance


#: The tolerances of ``FIGURES`` in words, for every table that marks agreement.
TOLERANCE_NOTE = ("savings within 2 points, lit on entry within 1 point, lag p95 within 0.5 s, "
                  "false on-time within 10 % of full, at least 1 s")

FIGURES = (
    Figure("savings_vs_always_on", "savings", "mean", 0.02),
    Figure("lit_on_entry_rate", "lit_on_entry", "mean", 0.01),
    Figure("lag_p95_s", "lag_p95_s", "mean", 0.5),
    Figure("false_on_time_s", "false_on_s", "sum", 0.10, relative=True, floor=1.0),
)


def validation_seeds(scenario: Scenario, count: int) -> list[int]:
    seeds = [scenario.seed + i for i in range(count)]
    clash = sorted(set(seeds) & {night.seed for night in calibration_nights(64)})
    if clash:
        raise RunError(f"seed: {clash[0]} is a calibration seed; pick a scenario seed below {CALIBRATION_SEED_BASE}")
    return seeds


def _pool(values: list, how: str) -> float | None:
    values = [v for v in values if v is not None]
    if not values:
        return None
    return float(sum(values)) if how == "sum" else float(sum(values) / len(values))


def compare_figures(full_runs: Sequence[dict], fast_runs: Sequence[dict]) -> dict[str, dict]:
    """Per controller label, per figure: full, fast, difference, tolerance and whether it agrees."""
    out: dict[str, dict] = {}
    for label in full_runs[0]["controllers"]:
        row = {}
        for fig in FIGURES:
            full = _pool([run["controllers"][label][fig.key] for run in full_runs], fig.pooled)
            fast = _pool([run["controllers"][label][fig.key] for run in fast_runs], fig.pooled)
            if full is None or fast is None:
                agrees, diff, allowed = full is None and fast is None, None, None
            else:
                diff, allowed = fast - full, fig.allowed(full)
                agrees = abs(diff) <= allowed + 1e-9
            row[fig.label] = {"full": full, "fast": fast, "diff": diff, "tolerance": allowed, "pass": agrees}
        out[label] = row
    return out


def validate(scenario: Scenario, *, seeds: int = DEFAULT_SEEDS, duration_s: float = DEFAULT_DURATION_S,
             controllers: Sequence[str] | None = None, cache_dir: Path | None = None, workers: int = 1,
             progress: bool = True) -> dict:  # fmt: skip
    """Run full and fast on the validation seeds; the comparison (see ``compare_figures``)."""
    model = sensor_model_for(scenario, cache_dir, progress=progress)
    full_runs, fast_runs = [], []
    for seed in validation_seeds(scenario, seeds):
        night = override(scenario, {"seed": seed, "duration_s": duration_s})
        full_runs.append(run_comparison(night, controllers, progress=progress, workers=workers, fidelity="full"))
        fast_runs.append(run_comparison(night, controllers, progress=progress, workers=1, fidelity="fast",
                                        sensor_model=model))  # fmt: skip
    return {"scenario": scenario.name, "seeds": validation_seeds(scenario, seeds), "duration_s": duration_s,
            "sensor_model": model.key, "controllers": compare_figures(full_runs, fast_runs)}  # fmt: skip


def _cell(value: float | None, label: str) -> str:
    if value is None:
        return "n/a"
    if label in ("savings", "lit_on_entry"):
        return f"{100 * value:.1f}%"
    return f"{value:.1f}"


def validation_table(result: dict) -> str:
    """The comparison as a text table: per controller and figure, full / fast and PASS or MISS."""
    labels = [f.label for f in FIGURES]
    head = f"{'controller':<19}" + "".join(f"  {label + ' full/fast':<28}" for label in labels)
    lines = [f"{result['scenario']}: seeds {result['seeds']}, {result['duration_s']:g} s each, "
             f"sensor model {result['sensor_model']}", head]  # fmt: skip
    passed = total = 0
    for name, row in result["controllers"].items():
        cells = []
        for label in labels:
            c = row[label]
            mark = "PASS" if c["pass"] else "MISS"
            passed, total = passed + c["pass"], total + 1
            cells.append(f"  {_cell(c['full'], label) + ' / ' + _cell(c['fast'], label) + ' ' + mark:<28}")
        lines.append(f"{name:<19}" + "".join(cells))
    lines.append(f"{passed} of {total} cells agree ({TOLERANCE_NOTE})")
    return "\n".join(lines)
