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
not written yet (the recorder runs beside the first controllers of a parallel comparison);
``rows_of`` gives the chunk's agents as columns too, for those who compute over every step of a
chunk in one numpy pass (fast mode's candidates).

A chunk holds compact arrays, not objects: per step the number of agents and the world's spawn
count; per agent and step its object, position, heading, speed and gait phase (float64, as
``World.states`` gives them, so nothing is rounded); per group member and step its gait phase;
and the looks (class, size, light, group members) of the objects first seen in that chunk.
"""

from __future__ import annotations

import os
import pickle
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from citysim.config.scenario import Scenario
from citysim.sim.night import build_night
from citysim.world.agents import AgentColumns, AgentState, MemberState, frozen_from_fields

#: physics steps per chunk file (60 s at 30 Hz): small enough to stream, few enough files
CHUNK_STEPS = 1800
#: the columns of a chunk's per-agent rows
DYNAMIC_COLUMNS = ("x_m", "y_m", "heading_rad", "speed_mps", "gait_phase_rad")
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

    def add(self, agents: list[AgentState], spawned_count: int) -> None:
        self.counts.append(len(agents))
        self.spawned.append(spawned_count)
        for a in agents:
            if a.object_id not in self.looks_seen:
                self.looks_seen.add(a.object_id)
                self.new_looks.append(_looks_of(a))
            self.objects.append(a.object_id)
            self.rows.append((a.x_m, a.y_m, a.heading_rad, a.speed_mps, a.gait_phase_rad))
            self.member_phases.extend(m.gait_phase_rad for m in a.members)
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

        def on_step(t_s: float, agents: list[AgentState]) -> None:
            writer.add(agents, night.spawned_count)
            steps[0] += 1

        night.start_physics(on_step)
        t, t_end = 0.0, scenario.duration_s
        while t < t_end - 1e-9:  # whole seconds, as the run loop's clock does
            t_next = min(t_end, t + 1.0)
            night.run_until(t_next)
            if on_progress is not None:
                on_progress(t_next - t)
            t = t_next
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
        self._steps: list[tuple[int, int, int, int]] = []  # per step: first row, rows, first member phase, spawned
        self._step_in_chunk = 0
        self._chunk: dict | None = None
        self._columns: AgentColumns | None = None  # the current chunk's, made on first ask
        self._latest: tuple[list[AgentState], int] = ([], 0)  # the latest step's agents and first row

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
        # where each step's rows and member phases start
        counts = chunk["counts"].tolist()
        objects = chunk["objects"].tolist()
        steps, row, member = [], 0, 0
        for n, spawned in zip(counts, chunk["spawned"].tolist(), strict=True):
            steps.append((row, n, member, spawned))
            member += sum(len(self.looks[oid].members) for oid in objects[row : row + n])
            row += n
        chunk["objects"], chunk["row_array"], chunk["rows"] = objects, chunk["rows"], chunk["rows"].tolist()
        chunk["member_phases"] = chunk["member_phases"].tolist()
        self._chunk, self._steps, self._step_in_chunk, self._chunk_index = chunk, steps, 0, index
        self._columns = None

    def next_step(self) -> list[AgentState]:
        """The agents after the next physics step (the world's ``states()`` then), bit for bit."""
        if self._chunk is None or self._step_in_chunk == len(self._steps):
            self._load(self._chunk_index + 1)
        first, n, member, self.spawned_count = self._steps[self._step_in_chunk]
        self._step_in_chunk += 1
        if not n:  # an empty street, most steps of a quiet hour
            self._latest = ([], first)
            return self._latest[0]
        chunk = self._chunk
        out = []
        for oid, (x, y, heading, speed, phase) in zip(
            chunk["objects"][first : first + n], chunk["rows"][first : first + n], strict=True
        ):
            looks = self.looks[oid]
            members = ()
            if looks.members:
                phases = chunk["member_phases"][member : member + len(looks.members)]
                member += len(looks.members)
                members = tuple(MemberState(*m, p) for m, p in zip(looks.members, phases, strict=True))
            out.append(frozen_from_fields(AgentState, {"object_id": oid, "cls": looks.cls, "x_m": x, "y_m": y, "heading_rad": heading,
                                     "speed_mps": speed, "length_m": looks.length_m, "width_m": looks.width_m,
                                     "height_m": looks.height_m, "gait_phase_rad": phase, "members": members,
                                     "light_on": looks.light_on}))  # fmt: skip
        self._latest = (out, first)
        return out

    def rows_of(self, agents: list[AgentState]) -> tuple[AgentColumns, int] | None:
        """The current chunk's agents as columns and the first row of ``agents``, when ``agents`` is
        the list the latest ``next_step`` gave (its agents are the ``len(agents)`` rows from there,
        the same numbers); else None."""
        latest, first = self._latest
        if agents is not latest or self._chunk is None:
            return None
        if self._columns is None:
            chunk = self._chunk
            rows, looks = chunk["row_array"], [self.looks[oid] for oid in chunk["objects"]]
            x_m, y_m, heading_rad, speed_mps = (np.ascontiguousarray(rows[:, DYNAMIC_COLUMNS.index(name)])
                                                for name in ("x_m", "y_m", "heading_rad", "speed_mps"))
            self._columns = AgentColumns(x_m, y_m, heading_rad, speed_mps, tuple(lk.cls for lk in looks),
                                         np.array([lk.light_on for lk in looks], dtype=bool))  # fmt: skip
        return self._columns, first


def recorded_steps(folder: Path) -> int:
    """Steps of a finished recording (``TrafficError`` if it is not finished)."""
    done = Path(folder) / _DONE
    if not done.exists():
        raise TrafficError(f"{folder}: no finished traffic recording")
    with open(done, "rb") as fh:
        return int(pickle.load(fh)["steps"])

