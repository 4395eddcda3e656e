"""Fast mode: a calibrated sensor model in place of rendering and the detector.

Owns the candidates a camera may see (``geometry``), the calibration records of full-fidelity
render-and-detect (``records``), the fitted model (``model``), the stand-ins camera controllers
use instead of the detector and the threshold segmenter (``sensors``) and the simpy process
that judges the cameras with them (``sense``). Calibrating and caching a scenario's model is
``citysim.sim.calibration``; comparing fast against full is ``citysim.sim.validation``.
"""

#: How a camera is simulated: "full" renders frames for the real detector; "fast" draws what it
#: would report from the calibrated sensor model, with no rendering.
FIDELITIES = ("full", "fast")
