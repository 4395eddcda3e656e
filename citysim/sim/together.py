"""A comparison's task: one or more controllers over one night, in step, writing their run files.

Every controller of ``citysim.sim.compare`` runs here, most alone (a group of one runs exactly
as ``citysim.sim.loop.run_controller`` runs it). Several full-fidelity camera controllers run in
step render each frame once:

Rendering is about two fifths of a full-fidelity camera controller's time (the rest is the
detector), and every camera controller of a comparison films the same street on the same
clock. Run a second at a time, one controller after the other, they ask for the same frames
within the same second, and ``citysim.sim.frames.SharedFrames`` hands a frame rendered for one
to all of those whose lamps all stand at the same levels. Each controller's summary, lamps.csv
and objects.csv are those of its run alone, bit for bit (``tests/citysim/sim/test_together.py``).

Measured on suburban_night it saves no time, so ``run_comparison`` runs it only when asked
(``share_frames=True``). Each controller's lamps differ somewhere most of the time
(``detector_located`` keeps the first lamp at full all night), and any difference, however far,
makes a frame another's: at 02:00 seven camera controllers asked for 12,034 frames over 120 s,
and in one group 27 % were shared. The frames shared are the cheap ones (an empty street under
the still view a renderer keeps): four camera controllers over 200 s at 23:00 rendered 8,064
frames in 5.9 CPU-s in step against 10,741 in 6.5 CPU-s one after the other, 33.9 against
34.4 CPU-s in all.
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
