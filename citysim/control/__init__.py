"""Switching the lamps: luminaires, controllers (a registry by name) and the radio network.

Imports world snapshots, config and detector; never render, metrics, sim or report."""
