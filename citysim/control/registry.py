"""Controllers by name: the scenario's ``controllers`` list and ``--controllers`` pick from these.

Adding a controller is one class (a module of control/) and one entry here.
"""

from __future__ import annotations

from citysim.control.base import Controller
from citysim.control.camera import Threshold05, Threshold5
from citysim.control.clock import AlwaysOn, Schedule
from citysim.control.detecting import (
    DetectorConfirmed,
    DetectorNetwork,
    DetectorPerFrame,
    DetectorTracked,
)
from citysim.control.fused import DetectorFused
from citysim.control.located import DetectorLocated
from citysim.control.oracle import Oracle
from citysim.control.oracle_seen import OracleSeen
from citysim.control.pir import PassiveInfrared

CONTROLLERS: dict[str, type[Controller]] = {
    cls.name: cls
    for cls in (
        AlwaysOn, Oracle, OracleSeen, Schedule, PassiveInfrared, Threshold5, Threshold05,
        DetectorPerFrame, DetectorConfirmed, DetectorTracked, DetectorNetwork, DetectorLocated,
        DetectorFused,
    )
}  # fmt: skip
