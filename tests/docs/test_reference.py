"""The generated reference pages hold every command, option and scenario field the code has."""

from __future__ import annotations

import argparse

from citysim.config.scenario import Scenario
from experiments.docs_site.reference import (
    citysim_subparsers,
    cli_page,
    detector_parsers,
    scenario_models,
    scenario_page,
    unit_of,
    yaml_comments,
)


def test_every_citysim_command_and_option_is_on_the_cli_page():
    page = cli_page()
    subparsers = citysim_subparsers()
    assert {"run", "render", "year", "sweep", "calibrate", "validate", "detect", "plot"} <= set(subparsers)
    for parser in [*subparsers.values(), *detector_parsers().values()]:
        assert f"## `{parser.prog}`" in page
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            for option in action.option_strings:
                assert f"`{option}`" in page, f"{parser.prog} {option} missing from the CLI reference"


def test_every_scenario_field_is_on_the_schema_page():
    page = scenario_page()
    models = dict((m, path) for path, m in scenario_models())
    assert Scenario in models
    assert len(models) >= 10, "the walk reaches the nested sections (street, lamps, traffic, ...)"
    for model, path in models.items():
        assert (f"## `{path}`" if path else "## top level") in page
        for name in model.model_fields:
            assert f"| `{name}` |" in page


def test_a_field_shows_its_unit_default_and_comment():
    page = scenario_page()
    hold = next(line for line in page.splitlines() if line.startswith("| `hold_s` | float |"))
    assert "| s |" in hold and "| `30.0` |" in hold and "after the last detection" in hold
    first = next(line for line in page.splitlines() if line.startswith("| `first_x_m` |"))
    assert "*suburban_night:* lamps at x = 45" in first  # no description in the model: the scenario's comment
    assert unit_of("speed_kmh") == "km/h" and unit_of("tilt_deg") == "degrees" and unit_of("name") == ""


def test_yaml_comments_follow_the_nesting():
    text = "a:\n  # above b\n  b: 1\n  c: 2   # on c\nd: 3\n"
    assert yaml_comments(text) == {"a.b": "above b", "a.c": "on c"}
