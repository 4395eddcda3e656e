"""The sentence under each figure of report.html: what the plot shows and how to read it.

Keyed by the PNG's file name (``vs_<axis>.png`` and ``heatmap_<metric>.png`` of a sweep by
their pattern). A plot without a caption here is a bug the tests catch: every figure the
report embeds must say what it is.
"""

from __future__ import annotations

import re

from citysim.report.frontier import HOW_TO_READ
from citysim.report.oracle_gap import HOW_TO_READ as GAP_HOW_TO_READ

__all__ = ["caption_for"]

#: file name -> (short title, how to read it)
CAPTIONS: dict[str, tuple[str, str]] = {
    "frontier.png": ("Savings against darkness: the planner's headline", HOW_TO_READ),
    "energy.png": (
        "Energy per controller",
        "Each bar is the energy one controller drew over the whole run, in kWh: the solid part is "
        "the light itself, the dotted part the drivers' standby power and the hatched part the "
        "sensors and their computers. The label over a bar is its saving against always-on, which "
        "keeps every lamp at full: a lower bar saves more, but read it together with the lag "
        "figures, since a controller that saves by leaving people below full level is no saving.",
    ),
    "oracle_gap.png": ("Where each controller spends beyond the bound, lamp by lamp", GAP_HOW_TO_READ),
    "energy_per_hour.png": (
        "Energy per hour of the night",
        "Energy drawn in each clock hour, one bar per controller, so you can see when a controller "
        "saves (a schedule only after its dimming hour, a sensing controller mostly in the quiet "
        "hours). A partial last hour has lower bars because it is shorter, not because it saves.",
    ),
    "lamp_levels.png": (
        "Light level of the busiest lamps",
        "One row per controller, one column per lamp (the lamps most objects passed), clock time "
        "across. The line is the lamp's true level (1 = full, the dim level when nobody is "
        "around); the bars under it are objects in that lamp's zone, one row per class. A good "
        "controller is at 1 before each bar starts and back to dim soon after it ends; a bar that "
        "starts under a dim line is someone walking into a zone below full level (dimmed, not off).",
    ),
    "lag_cdf.png": (
        "Illumination lag per class",
        "For each class, the share of zone entries whose lamp was at full within the lag on the "
        "x axis (0 s = already lit on entry); a curve that jumps high at 0 s and stays there is "
        "best. Entries whose lamp never reached full while the object was in the zone have no lag: "
        "they are the bars to the right of each panel, and each curve stops at the share that was "
        "lit.",
    ),
    "coverage.png": (
        "Where the cameras can see",
        "The street from above with each camera's field of view (yellow). A green cell of a lane "
        "or sidewalk is ground where some lamp camera sees a person whole within the detector's "
        "range; a red cell is ground no camera sees, and the red bars along the top are stretches "
        "of street where no camera sees anything across the whole width. People crossing red "
        "ground are found late or not at all by a camera controller, whatever its settings.",
    ),
    "energy_per_hour_sweep": (
        "Energy per hour of the night (sweep)",
        "Mean energy drawn in each clock hour over every finished point of the sweep, one bar per "
        "controller: when in the night each controller saves.",
    ),
}

_VS_AXIS = (
    "Savings and lag along {axis}",
    "Left: energy savings against always-on as {axis} changes; right: the 95th percentile of "
    "illumination lag. The line is the mean over seeds and the other axes, the shaded band their "
    "range: a setting is good when savings are high and the lag stays low over the whole band.",
)
_HEATMAP = (
    "Heatmap: {metric}",
    "Each cell is one combination of the two swept settings (mean over seeds), one panel per "
    "controller, all on one colour scale; the number in a cell is its value. Grey cells have no "
    "data and cells marked 'failed' are points that did not run.",
)


def caption_for(filename: str, kind: str = "run", names: dict[str, str] | None = None) -> tuple[str, str]:
    """(short title, sentence) for a plot file of a run or sweep folder (``kind``).

    ``names`` maps the variable part of a sweep file name (the axis slug of ``vs_<slug>.png``,
    the metric key of ``heatmap_<key>.png``) to words for people; unmapped parts are un-slugged.
    """
    names = names or {}
    if kind == "sweep" and filename == "energy_per_hour.png":
        return CAPTIONS["energy_per_hour_sweep"]
    if filename in CAPTIONS:
        return CAPTIONS[filename]
    for pattern, (title, text) in ((r"vs_(.+)\.png", _VS_AXIS), (r"heatmap_(.+)\.png", _HEATMAP)):
        m = re.fullmatch(pattern, filename)
        if m:
            words = names.get(m.group(1), m.group(1).replace("_", " "))
            return title.format(axis=words, metric=words), text.format(axis=words, metric=words)
    raise KeyError(f"no caption for plot {filename}: add one to citysim.report.captions")
