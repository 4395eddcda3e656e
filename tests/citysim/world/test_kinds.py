"""The kinds registry: every record resolves in every registry that reads it, and the
scenario schema, metrics and plots follow it."""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest

from citysim.config.kinds import AGENT_KINDS, DETECTOR_CLASSES, TARGET_KINDS
from citysim.config.scenario import NeighboursAhead, load_scenario
from citysim.config.traffic import TRAFFIC_SPECS, TrafficClasses
from citysim.metrics.confusion import CONFUSION_CLASSES, scored_as
from citysim.metrics.zones import DEFAULT_LOOKAHEAD_S
from citysim.render.beams import BEAMS
from citysim.render.models import AGENT_MODELS
from citysim.report.common import CLASS_COLORS
from citysim.world.agents import BODY_RECIPES
from citysim.world.traffic import ROUTE_PLANNERS

SUBURBAN = Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml"


@pytest.mark.parametrize("name", sorted(AGENT_KINDS))
def test_every_kind_resolves_in_every_registry(name: str) -> None:
    kind = AGENT_KINDS[name]
    assert kind.name == name
    assert kind.body.recipe in BODY_RECIPES
    assert kind.route in ROUTE_PLANNERS
    assert kind.shape in AGENT_MODELS
    assert kind.beam is None or kind.beam in BEAMS
    assert name in TrafficClasses.model_fields and TRAFFIC_SPECS[name].kind == name
    if kind.is_target:
        assert name in CLASS_COLORS and name in DEFAULT_LOOKAHEAD_S
    assert scored_as(name) == kind.detector_class


def test_detector_classes_are_the_detectors() -> None:
    from detector.classes import CLASSES

    assert DETECTOR_CLASSES == CLASSES == CONFUSION_CLASSES


def test_network_neighbours_follow_the_detector_classes() -> None:
    # the detector reports classes, so only kinds that are one get a lamps-ahead setting
    assert tuple(NeighboursAhead.model_fields) == DETECTOR_CLASSES[1:]
    assert NeighboursAhead().vehicle == AGENT_KINDS["vehicle"].lamps_ahead == 4


def test_traffic_classes_follow_the_registry_and_pickle() -> None:
    scenario = load_scenario(SUBURBAN)
    assert tuple(TrafficClasses.model_fields) == tuple(AGENT_KINDS)
    assert [s.kind for s in scenario.traffic.classes.all()] == list(AGENT_KINDS)
    # per-kind defaults come from the records
    assert TRAFFIC_SPECS["cyclist"]().lights_fraction == AGENT_KINDS["cyclist"].lit_share == 0.8
    assert TRAFFIC_SPECS["group"]().crossing_fraction == AGENT_KINDS["group"].crossing_share
    # scenarios go to worker processes
    assert pickle.loads(pickle.dumps(scenario)) == scenario


def test_reported_kinds_are_the_detector_classes_plus_kinds_with_traffic() -> None:
    scenario = load_scenario(SUBURBAN)
    reported = scenario.traffic.reported_kinds()
    assert reported[:4] == ("pedestrian", "group", "cyclist", "vehicle")
    assert set(reported) <= set(TARGET_KINDS)
