"""The lamp cameras' frames of a run, rendered on demand and, for controllers run in step, shared.

A frame of camera i at frame index k shows the agents of the latest physics step under the
lamps' levels at that time, with noise and rain that are a function of k and the camera's seed
(``CameraRenderer.render`` with ``frame_index``). Every controller of a comparison replays the
same agents on the same clock, so two controllers whose lamps stand at the same levels when
camera i takes frame k see the same frame, bit for bit. A ``SharedFrames`` cache hands such a
frame, rendered once, to each of them: controllers run in step (``citysim.sim.together``) ask
for the frames of one simulated second in turn, and the frames are kept until the next second.

The key is every lamp's level, not only the levels of the lamps near the camera: the renderer
shades the background and the agents with every lamp whose light reaches the view (on
suburban_night every lamp reaches every camera's view, if only by a fraction of a grey level),
and a shared frame must be the frame the controller would have rendered itself, to the last bit.
So frames are shared only where the controllers' lamps all stand alike. A shared frame is
read-only, so a detector that wrote into its input would fail loudly instead of changing another's
frame.

Each controller still renders with its own renderers: a renderer keeps the lit still view of the
levels it last drew, and one renderer drawing for several controllers in turn rebuilt it at
nearly every frame (four controllers at 23:00: 8,064 renders took 11.9 CPU-s on shared
renderers against 6.4 CPU-s for 10,741 on their own).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


class SharedFrames:
    """One simulated second of frames, by (camera, frame index, every lamp's level), for the
    controllers run in step; counts how many were rendered and how many handed out again."""

    def __init__(self) -> None:
        self._second: dict[tuple[int, int, bytes], object] = {}
        self.rendered = 0
        self.reused = 0

    def frame(self, renderer, camera_index: int, frame_index: int, t_s: float, agents, lamp_levels):
        """The frame as ``CameraFrames.frame`` gives it: handed out again if a controller in step
        already asked for it under the same levels, else rendered by ``renderer`` (the asking
        controller's own) and kept, read-only, until ``next_second``."""
        key = (camera_index, frame_index, np.asarray(lamp_levels, dtype=np.float64).tobytes())
        frame = self._second.get(key)
        if frame is None:
            frame = renderer.render(t_s, agents, lamp_levels, frame_index=frame_index)
            frame.image.flags.writeable = False  # a fresh array (FrameOutput.finish), now shared
            self._second[key] = frame
            self.rendered += 1
        else:
            self.reused += 1
        return frame

    def next_second(self) -> None:
        """Every controller in step has taken this second's frames: forget them."""
        self._second.clear()


class CameraFrames:
    """Frames of every camera (``Street.cameras`` order) from a controller's own renderers; with
    ``shared``, taken from and given to the frames of the controllers run in step with it."""

    def __init__(self, renderers: Sequence, shared: SharedFrames | None = None):
        self.renderers = list(renderers)
        self.shared = shared

    def frame(self, camera_index: int, frame_index: int, t_s: float, agents, lamp_levels):
        """Camera ``camera_index``'s frame ``frame_index`` at ``t_s`` (s) showing ``agents`` under
        ``lamp_levels`` (one per street lamp, 0..1): a ``citysim.render.camera.RenderedFrame``."""
        renderer = self.renderers[camera_index]
        if self.shared is None:
            return renderer.render(t_s, agents, lamp_levels, frame_index=frame_index)
        return self.shared.frame(renderer, camera_index, frame_index, t_s, agents, lamp_levels)
