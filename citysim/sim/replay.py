"""Traffic simulated once per run and replayed to every controller.

The world never depends on the controller: ``citysim.world`` imports only ``citysim.config``;
the world is stepped by its own process on fixed times k / physics_hz; arrivals and the world
draw from the "traffic" and "world" streams, which no controller, camera or radio touches. So
every controller of a comparison would step the same pymunk world to the same agents; stepping it
once and handing the snapshots to every controller gives them bit for bit the same agents.

``record_traffic(scenario, folder)`` steps the night's world alone (no controller) and writes its
agent snapshots as chunk files of ``CHUNK_STEPS`` physics steps, each written whole and then
renamed into place, so a reader in another process sees a chunk complete or not at all.
``TrafficReplay(folder)`` reads them back, in step order, waiting for a chunk the recorder has
not written yet (the recorder runs beside the first controllers of a parallel comparison). Each
step's agents are a ``citysim.sim.recorded.RecordedAgents``, whose snapshots are made when first
read; its ``chunk`` (and ``rows_of``) gives the chunk's agents as columns too, for those who
compute over every step of a chunk in one numpy pass (the metrics, the oracle, fast mode's
candidates).

A chunk holds compact arrays, not objects: per step the number of agents and the world's spawn
count; per agent and step its object, position, heading, speed and gait phase (float64, as
``World.states`` gives them, so nothing is rounded); per group member and step its gait phase;
and the looks (class, size, light, group members) of the objects first seen in that chunk.
"""

from __future__ import annotations

import os
import pickle
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from citysim.config.scenario import Scenario
from citysim.sim.night import build_night
from citysim.sim.recorded import DYNAMIC_COLUMNS, RecordedAgents, RecordedChunk
from citysim.world.agents import AgentColumns, AgentState

#: physics steps per chunk file (60 s at 30 Hz): small enough to stream, few enough files
CHUNK_STEPS = 1800
_DONE = "done.pkl"
_FAILED = "failed.txt"


class TrafficError(RuntimeError):
    """The recording is missing, incomplete or written by a recorder that failed."""


@dataclass(frozen=True)
class _Looks:
    """What does not change while an object is in the street (``AgentState`` less its motion)."""

    object_id: int
    cls: str
    length_m: float
    width_m: float
    height_m: float
    light_on: bool
    members: tuple[tuple[float, float, float, float, float], ...]  # forward, left, width, height, length


def _looks_of(agent: AgentState) -> _Looks:
    members = tuple((m.forward_m, m.left_m, m.width_m, m.height_m, m.length_m) for m in agent.members)
    return _Looks(agent.object_id, agent.cls, agent.length_m, agent.width_m, agent.height_m, agent.light_on, members)


class _ChunkWriter:
    """Collects snapshots step by step; ``flush`` writes them as one chunk file."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.index = 0
        self.looks_seen: set[int] = set()
        self._reset()

    def _reset(self) -> None:
        self.counts: list[int] = []
        self.spawned: list[int] = []
        self.objects: list[int] = []
        self.rows: list[tuple[float, ...]] = []
        self.member_phases: list[float] = []
        self.new_looks: list[_Looks] = []

    def add_rows(self, world, spawned_count: int) -> None:
        """The world's agents after a step, from ``World.snapshot_rows`` (the values of
        ``World.states()``, without a snapshot per agent; snapshots are made only in the steps
        where an object is first seen, for its looks)."""
        objects, rows, member_phases = world.snapshot_rows()
        self.counts.append(len(objects))
        self.spawned.append(spawned_count)
        new = [oid for oid in objects if oid not in self.looks_seen]
        if new:
            by_id = {a.object_id: a for a in world.states()}
            for oid in new:
                self.looks_seen.add(oid)
                self.new_looks.append(_looks_of(by_id[oid]))
        self.objects.extend(objects)
        self.rows.extend(rows)
        self.member_phases.extend(member_phases)
        if len(self.counts) == CHUNK_STEPS:
            self.flush()

    def flush(self) -> None:
        if not self.counts:
            return
        chunk = {
            "counts": np.array(self.counts, np.int32),
            "spawned": np.array(self.spawned, np.int64),
            "objects": np.array(self.objects, np.int64),
            "rows": np.array(self.rows, np.float64).reshape(-1, len(DYNAMIC_COLUMNS)),
            "member_phases": np.array(self.member_phases, np.float64),
            "looks": self.new_looks,
        }
        _write_whole(self.folder / f"chunk_{self.index:06d}.pkl", chunk)
        self.index += 1
        self._reset()


def _write_whole(path: Path, obj) -> None:
    """Write ``obj`` to a temporary name, then rename: readers never see half a file."""
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as fh:
        pickle.dump(obj, fh, protocol=pickle.HIGHEST_PROTOCOL)
    os.replace(tmp, path)


def record_traffic(
    scenario: Scenario, folder: Path, on_progress: Callable[[float], None] | None = None
) -> int:
    """Step the scenario's world alone to its end and write every physics step's agents into
    ``folder`` (created); returns the number of steps. A failure leaves ``failed.txt`` naming it,
    so readers waiting for chunks stop instead of hanging."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    try:
        night = build_night(scenario)
        writer = _ChunkWriter(folder)
        steps = [0]

        def on_step(t_s: float, _agents) -> None:
            writer.add_rows(night.world, night.spawned_count)
            steps[0] += 1

        night.start_physics(on_step, snapshots=False)  # the rows alone: a snapshot per agent was a quarter of the recorder's CPU
        night.run_whole_seconds(on_progress=on_progress)  # whole seconds, as the run loop's clock does
        writer.flush()
        _write_whole(folder / _DONE, {"steps": steps[0], "chunks": writer.index})
        return steps[0]
    except BaseException as exc:
        (folder / _FAILED).write_text(f"traffic recording failed: {exc!r}\n")
        raise


class TrafficReplay:
    """The recorded agents of each physics step, in step order (``next_step``).

    ``wait_s``: how long to wait for a chunk the recorder has not written yet before giving up.
    """

    POLL_S = 0.05

    def __init__(self, folder: Path, wait_s: float = 3600.0):
        self.folder = Path(folder)
        self.wait_s = wait_s
        self.looks: dict[int, _Looks] = {}
        self.spawned_count = 0
        self._chunk_index = -1
        self._chunk: RecordedChunk | None = None
        self._step_in_chunk = 0
        self._latest: RecordedAgents | None = None  # the latest step's agents

    def _load(self, index: int) -> None:
        path = self.folder / f"chunk_{index:06d}.pkl"
        deadline = time.monotonic() + self.wait_s
        while not path.exists():
            if (self.folder / _FAILED).exists():
                raise TrafficError((self.folder / _FAILED).read_text().strip())
            if (self.folder / _DONE).exists() and not path.exists():
                raise TrafficError(f"{self.folder}: the recording ends before chunk {index} (a longer run than recorded?)")
            if time.monotonic() > deadline:
                raise TrafficError(f"{path}: not written within {self.wait_s:.0f} s")
            time.sleep(self.POLL_S)
        with open(path, "rb") as fh:
            chunk = pickle.load(fh)
        for looks in chunk["looks"]:
            self.looks[looks.object_id] = looks
        self._chunk, self._step_in_chunk, self._chunk_index = RecordedChunk(chunk, self.looks), 0, index

    def next_step(self) -> RecordedAgents:
        """The agents after the next physics step (the world's ``states()`` then), bit for bit; their
        snapshots are made when first read (``citysim.sim.recorded``)."""
        if self._chunk is None or self._step_in_chunk == self._chunk.n_steps:
            self._load(self._chunk_index + 1)
        step = self._step_in_chunk
        self._step_in_chunk += 1
        self.spawned_count = self._chunk.spawned[step]
        self._latest = RecordedAgents(self._chunk, step)
        return self._latest

    def rows_of(self, agents: Sequence[AgentState]) -> tuple[AgentColumns, int] | None:
        """The current chunk's agents as columns and the first row of ``agents``, when ``agents`` is
        the sequence the latest ``next_step`` gave (its agents are the ``len(agents)`` rows from
        there, the same numbers); else None."""
        latest = self._latest
        if agents is not latest or latest is None:
            return None
        return latest.chunk.columns, latest.first


def recorded_steps(folder: Path) -> int:
    """Steps of a finished recording (``TrafficError`` if it is not finished)."""
    done = Path(folder) / _DONE
    if not done.exists():
        raise TrafficError(f"{folder}: no finished traffic recording")
    with open(done, "rb") as fh:
        return int(pickle.load(fh)["steps"])

