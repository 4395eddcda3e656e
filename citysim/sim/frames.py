"""The lamp cameras' frames of a run, rendered on demand and, for controllers run in step, shared.

A frame of camera i at frame index k shows the agents of the latest physics step under the
lamps' levels at that time, with noise and rain that are a function of k and the camera's seed
(``CameraRenderer.render`` with ``frame_index``). Every controller of a comparison replays the
same agents on the same clock, so two controllers whose lamps stand at the same levels when
camera i takes frame k see the same frame, bit for bit. ``CameraFrames.shared`` renders such a
frame once and hands it to each of them: controllers run in step (``citysim.sim.together``) ask
for the frames of one simulated second in turn, and the frames are kept until the next second.

The key is every lamp's level, not only the levels of the lamps near the camera: the renderer
shades the background and the agents with every lamp whose light reaches the view (on
suburban_night every lamp reaches every camera's view, if only by a fraction of a grey level),
and a shared frame must be the frame the controller would have rendered itself, to the last bit.
So frames are shared only where the controllers' lamps all stand alike. A shared frame is read-only, so a
detector that wrote into its input would fail loudly instead of changing another's frame.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


class CameraFrames:
    """Frames of every camera (``Street.cameras`` order) from its renderer; ``shared`` keeps one
    simulated second of them to hand to every controller that asks with the same lamp levels."""

    def __init__(self, renderers: Sequence, shared: bool = False):
        self.renderers = list(renderers)
        self.shared = shared
        self._second: dict[tuple[int, int, bytes], object] = {}
        self.rendered = 0  # frames rendered
        self.reused = 0  # frames handed out again from the second's cache

    def frame(self, camera_index: int, frame_index: int, t_s: float, agents, lamp_levels):
        """Camera ``camera_index``'s frame ``frame_index`` at ``t_s`` (s) showing ``agents`` under
        ``lamp_levels`` (one per street lamp, 0..1): a ``citysim.render.camera.RenderedFrame``."""
        if not self.shared:
            self.rendered += 1
            return self.renderers[camera_index].render(t_s, agents, lamp_levels, frame_index=frame_index)
        key = (camera_index, frame_index, np.asarray(lamp_levels, dtype=np.float64).tobytes())
        frame = self._second.get(key)
        if frame is None:
            frame = self.renderers[camera_index].render(t_s, agents, lamp_levels, frame_index=frame_index)
            # a copy no one else holds (cheap beside the render: ~0.1 MB), made read-only
            image = frame.image.copy()
            image.flags.writeable = False
            frame = type(frame)(image, frame.truth)
            self._second[key] = frame
            self.rendered += 1
        else:
            self.reused += 1
        return frame

    def next_second(self) -> None:
        """Every controller in step has taken this second's frames: forget them."""
        self._second.clear()
