"""Figures of a run: energy, zone lag and darkness, detection confusion, streaming quantiles.

Reads lamps and world snapshots (imports control, world, config); never sim, report or cli."""
