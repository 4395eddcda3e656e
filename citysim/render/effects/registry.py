"""The camera effects by name, in the order they are built and drawn.

The order is part of the random streams: the noise bank is drawn first, then the insects' seed,
from the renderer's generator. A new effect goes at the end (earlier seeds stay as they are).
"""

from __future__ import annotations

from citysim.render.effects.insects import InsectsEffect
from citysim.render.effects.noise import Noise
from citysim.render.effects.rain import Rain

EFFECTS = {"noise": Noise, "rain": Rain, "insects": InsectsEffect}
