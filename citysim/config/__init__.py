"""Scenario files: the frozen, validated Scenario a run is built from.

The lowest layer of citysim: imports only the detector and the standard stack, never world, render,
control, metrics or sim code, so anything may read a scenario."""
