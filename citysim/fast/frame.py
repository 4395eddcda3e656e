"""What fast mode passes where a camera frame would be: the camera's shape and its truth boxes.

The truth of a judged frame is read by ``citysim.metrics.confusion``, which needs the boxes only
to match them against detections (IoU); most frames with someone in view have no detection, and
projecting the boxes was a tenth of a camera controller's cost. So a ``SensedTruth`` projects its
box on the first read of x, y, w or h, from the agents of the frame it was made for.

``sensors`` below is the ``citysim.fast.sensors.FastSensors`` that makes these objects; it is not
imported here (that module imports this one).
"""

#: Detector range, m: beyond it a candidate is not 'fully visible' truth for the confusion figures.
DETECTOR_RANGE_M = 25.0


class SensedTruth:
    """A truth box as ``citysim.metrics.confusion`` reads it (attributes of a render TruthObject);
    the box (x, y, w, h, px) is projected when first read, which must be during its frame."""

    __slots__ = ("object_id", "cls", "fully_visible", "_sensors", "_agents", "_lamp_index", "_agent_index", "_box")

    def __init__(self, sensors, lamp_index: int, agent_index: int, fully_visible: bool):
        agent = sensors.step_agents[agent_index]  # its id and class (the step's snapshots not made)
        self.object_id: int = agent.object_id
        self.cls: str = agent.cls
        self.fully_visible = fully_visible
        self._sensors, self._agents = sensors, sensors.agents
        self._lamp_index, self._agent_index = lamp_index, agent_index
        self._box: tuple[int, int, int, int] | None = None

    @property
    def box_px(self) -> tuple[int, int, int, int]:
        if self._box is None:
            if self._sensors.agents is not self._agents:  # the sensors moved on: the index means another agent
                raise RuntimeError("SensedTruth: a frame's boxes are read during that frame")
            self._box = self._sensors.box_px(self._lamp_index, self._agent_index)
        return self._box

    @property
    def x(self) -> int:
        return (self._box or self.box_px)[0]  # the box once projected, without a second property call

    @property
    def y(self) -> int:
        return (self._box or self.box_px)[1]  # the box once projected, without a second property call

    @property
    def w(self) -> int:
        return (self._box or self.box_px)[2]  # the box once projected, without a second property call

    @property
    def h(self) -> int:
        return (self._box or self.box_px)[3]  # the box once projected, without a second property call


class SensedFrame:
    """What fast mode passes where a frame would be: the camera's shape and its candidates' truth."""

    __slots__ = ("shape", "sensors", "lamp_index", "_truth")

    def __init__(self, sensors, lamp_index: int):
        self.shape = sensors.frame_shapes[lamp_index]  # (height, width) px
        self.sensors = sensors
        self.lamp_index = lamp_index
        self._truth: tuple | None = None

    @property
    def truth(self) -> tuple:
        if self._truth is None:
            s, i = self.sensors, self.lamp_index
            if not s.any_agents or not s.step_pairs().counts[i]:  # no candidate in view
                self._truth = ()
            else:  # the camera's candidates and their forward distances, from the step's lists
                pairs = s.step_pairs()
                first, end = pairs.bounds(i)
                agents, forward_m = pairs.agents[first:end], pairs.forward_m[first:end]
                self._truth = tuple([SensedTruth(s, i, j, f_m <= DETECTOR_RANGE_M)
                                     for j, f_m in zip(agents, forward_m, strict=True)])  # fmt: skip
        return self._truth
