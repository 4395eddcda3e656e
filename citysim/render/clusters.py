"""Agents drawn together: clusters of agents that share one smear, and their compositing.

The painter (``citysim.render.agents``) fills every agent's parts by rank into
one buffer; this module splits the agents into *clusters* - boxes close
together, image motions alike (``citysim.render.kernels.group_boxes``) - and turns
each cluster's ranks into radiance on the frame in one go:

* parts behind a nearer standing surface (``occluder_depth``) are cut out;
* sharp clusters (no motion worth a blur) take their parts' radiance and
  labels directly;
* moving clusters are smeared by their mean motion (radiance and coverage,
  stacked in one buffer for a single filter pass), cut again where the smear
  reaches behind a surface nearer than all members, and composited over the
  frame; each covered pixel (coverage > 1/2) is labelled with the member there
  at mid-exposure.

Conventions: canvas pixels of ``citysim.render.canvas``, boxes (x0, y0, x1,
y1) with exclusive ends, radiance in linear full-scale units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from citysim.render.blur import (
    MIN_BLUR_PX,
    SHARED_BLUR_FRACTION,
    SHARED_BLUR_PX,
    smear_stacked,
    stacked_layers,
)
from citysim.render.kernels import (
    cut_behind,
    group_boxes,
    paint_sharp,
    paint_smeared,
    rank_layers,
)


@dataclass(frozen=True)
class PaintFrame:
    """Per-agent figures of one paint call (plain lists: read one agent at a time) and the
    frame's buffers."""

    rois: list[tuple[int, int, int, int]]  # canvas boxes (x0, y0, x1, y1), blur margins in
    dist: list[float]
    motion: list[tuple[float, float]]  # canvas px from time t back to t - exposure
    cut: list[bool]  # a standing surface in its box is nearer than the agent
    img: np.ndarray
    occluder_depth: np.ndarray
    labels: np.ndarray
    boxes: list[tuple[int, int, int, int]]  # canvas boxes drawn on, filled as clusters are drawn


#: Two boxes are one cluster when their joint box holds at most this many more pixels
#: than the two apart (a cluster costs about as much as smearing this many more pixels).
CLUSTER_SLACK_PX = 4000


@dataclass
class Cluster:
    """Agents drawn in one go: one blur (their mean motion), one box."""

    members: list[int]
    box: list[int]  # x0, y0, x1, y1
    motion_sum: list[float]

    @property
    def motion(self) -> tuple[float, float]:
        k = len(self.members)
        return self.motion_sum[0] / k, self.motion_sum[1] / k


def clusters(agents: list[int], ctx: PaintFrame) -> list[Cluster]:
    """Agents (far to near) split into clusters: boxes close together, image motions alike
    (within SHARED_BLUR_PX or SHARED_BLUR_FRACTION; ``citysim.render.kernels.group_boxes``). Clusters come
    far to near (by their nearest member)."""
    if not agents:
        return []
    n = len(agents)
    cluster_of = np.empty(n, np.int64)
    joint = np.empty((n, 6))
    k = group_boxes(
        np.array([ctx.rois[i] for i in agents], np.int64),
        np.array([ctx.motion[i] for i in agents], np.float64).reshape(n, 2),
        CLUSTER_SLACK_PX,
        SHARED_BLUR_PX,
        SHARED_BLUR_FRACTION,
        cluster_of,
        joint,
    )
    members: list[list[int]] = [[] for _ in range(k)]
    for i, c in zip(agents, cluster_of.tolist(), strict=True):
        members[c].append(i)
    out = [
        Cluster(m, [int(v) for v in row[:4]], row[4:])
        for m, row in zip(members, joint[:k].tolist(), strict=True)
    ]
    out.sort(key=lambda c: -ctx.dist[c.members[-1]])
    return out


def composite(
    ranks_buffer: np.ndarray,
    cluster: Cluster,
    ctx: PaintFrame,
    lut: np.ndarray,
    names: np.ndarray,
    mine: np.ndarray,
    first: dict[int, int],
    end: dict[int, int],
) -> None:
    """Occlusion cut, blur, composite and label one cluster of agents whose parts are drawn
    by rank in ``ranks_buffer`` (canvas); ``lut``, ``names`` and ``mine`` give the radiance,
    label and 1.0 for its members' part ranks (0 for others), ``first`` and ``end`` each
    member's first rank and one past its last."""
    members = cluster.members
    x0, y0, x1, y1 = cluster.box
    ranks = ranks_buffer[y0:y1, x0:x1]
    depth = ctx.occluder_depth[y0:y1, x0:x1]
    cut = [i for i in members if ctx.cut[i]]
    if cut:
        # parts behind a nearer standing surface at time t are taken out before the smear
        dist = np.zeros(256, np.float32)
        for i in cut:
            dist[first[i] : end[i]] = ctx.dist[i]
        cut_behind(ranks, depth, dist)
    view = ctx.img[y0:y1, x0:x1]
    out = ctx.labels[y0:y1, x0:x1]
    du, dv = cluster.motion
    if math.hypot(du, dv) < MIN_BLUR_PX:
        # sharp: each member pixel simply takes the part's radiance and the member's label
        paint_sharp(ranks, lut, names, view, out)
        return
    h, w = ranks.shape
    buf, second = stacked_layers(h, w, du, dv)
    rank_layers(ranks, lut, mine, buf, second)
    buf = smear_stacked(buf, du, dv)
    # ... and nothing the smear carries behind a surface nearer than all of them
    nearest_m = min(ctx.dist[i] for i in members) if cut else -math.inf
    # each covered pixel belongs to the member there at mid-exposure
    label = members[0] + 1 if len(members) == 1 else 0
    paint_smeared(
        buf[:h],
        buf[second:],
        depth,
        nearest_m,
        view,
        out,
        label,
        ranks,
        names,
        round(du / 2),
        round(dv / 2),
    )
