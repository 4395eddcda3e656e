"""A comparison's task: one or more controllers over one night, in step, writing their run files.

Every controller of ``citysim.sim.compare`` runs here, most alone (a group of one runs exactly
as ``citysim.sim.loop.run_controller`` runs it). Several full-fidelity camera controllers run in
step render each frame once (``citysim.sim.frames.SharedFrames``); each controller's files are
those of its run alone, bit for bit. Only when asked (``share_frames=True``).

Design: docs/design/modules.md (Controllers in step, sharing frames)
"""

from __future__ import annotations

import csv
from collections.abc import Callable, Sequence
from contextlib import ExitStack
from pathlib import Path

from citysim.config.scenario import ControllerSpec, Scenario
from citysim.sim.frames import SharedFrames
from citysim.sim.loop import ControllerRun
from citysim.sim.night import whole_seconds


def part_path(part_dir: Path, label: str, kind: str) -> Path:
    """Where controller ``label`` writes its part of the run's ``kind`` file (lamps, objects)."""
    return part_dir / f"{label}.{kind}.csv"


def run_together(
    scenario: Scenario,
    specs: Sequence[ControllerSpec],
    part_dir: Path,
    *,
    traffic: Path | None = None,
    fidelity: str = "full",
    sensor_model=None,
    on_progress: Callable[[float], None] | None = None,
) -> tuple[dict[str, dict], SharedFrames | None]:
    """Every controller of ``specs`` on the scenario's night, a simulated second at a time, each
    writing its part of lamps.csv / objects.csv into ``part_dir`` (``part_path``) and replaying ``traffic`` if given. Two or more at full fidelity share
    their frames; one alone runs exactly as ``citysim.sim.loop.run_controller`` runs it. Returns
    the summaries by display name and the shared frames (their counts say how many were reused;
    None when nothing was shared). ``on_progress(dt_s)`` after each controller's second.
    """
    part_dir.mkdir(parents=True, exist_ok=True)
    shared = SharedFrames() if fidelity == "full" and len(specs) > 1 else None
    with ExitStack() as files:
        runs = []
        for spec in specs:
            label = spec.display_name
            lamps_file = files.enter_context(open(part_path(part_dir, label, "lamps"), "w", newline=""))
            objects_file = files.enter_context(open(part_path(part_dir, label, "objects"), "w", newline=""))
            runs.append(ControllerRun(scenario, spec, lamps_writer=csv.writer(lamps_file),
                                      objects_writer=csv.writer(objects_file), traffic=traffic,
                                      fidelity=fidelity, sensor_model=sensor_model, shared_frames=shared))  # fmt: skip
        for t_s in whole_seconds(scenario.duration_s):
            for run in runs:
                t_next_s = run.night.run_second(t_s, run.on_second)
                if on_progress is not None:
                    on_progress(t_next_s - t_s)
            if shared is not None:
                shared.next_second()
        return {spec.display_name: run.summary() for spec, run in zip(specs, runs, strict=True)}, shared
