"""Several full-fidelity camera controllers over one night, in step, rendering each frame once.

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


def run_together(
    scenario: Scenario,
    specs: Sequence[ControllerSpec],
    part_dir: Path,
    *,
    traffic: Path | None = None,
    on_progress: Callable[[float], None] | None = None,
) -> tuple[dict[str, dict], SharedFrames]:
    """Every controller of ``specs`` at full fidelity on the scenario's night, a simulated second
    at a time, each writing its part of lamps.csv / objects.csv into ``part_dir`` (as
    ``citysim.sim.compare.run_to_files`` does) and replaying ``traffic`` if given. Returns the
    summaries by display name and the shared frames (their counts say how many were reused).
    ``on_progress(dt_s)`` after each controller's second.
    """
    part_dir.mkdir(parents=True, exist_ok=True)
    frames = SharedFrames()
    with ExitStack() as files:
        runs = []
        for spec in specs:
            label = spec.display_name
            lamps_file = files.enter_context(open(part_dir / f"{label}.lamps.csv", "w", newline=""))
            objects_file = files.enter_context(open(part_dir / f"{label}.objects.csv", "w", newline=""))
            runs.append(ControllerRun(scenario, spec, lamps_writer=csv.writer(lamps_file),
                                      objects_writer=csv.writer(objects_file), traffic=traffic,
                                      fidelity="full", shared_frames=frames))  # fmt: skip
        t_s = 0.0
        while t_s < scenario.duration_s - 1e-9:
            for run in runs:
                t_next_s = run.night.run_second(t_s, run.on_second)
                if on_progress is not None:
                    on_progress(t_next_s - t_s)
            frames.next_second()
            t_s = t_next_s
        return {spec.display_name: run.summary() for spec, run in zip(specs, runs, strict=True)}, frames
