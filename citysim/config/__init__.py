"""Scenario files: the frozen, validated Scenario a run is built from, and its vocabulary: the
road-user kinds as data (config.kinds), speeds and motion parameters (config.motion).

The lowest layer of citysim: imports only the detector and the standard stack, never world, render,
control, metrics or sim code, so anything may read a scenario."""
