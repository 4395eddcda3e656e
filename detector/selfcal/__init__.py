"""Self-calibration: a camera's height and tilt estimated from the people walking through its video.
Owns the walkers' image tracks (``walkers``), the estimate (``solve``) and ``python -m detector calibrate`` (``cli``)."""
