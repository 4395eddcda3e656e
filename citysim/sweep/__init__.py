"""Parameter sweeps: sweep files, the Dask runner and the resumable results table.

Imports config and sim; never report or cli."""
