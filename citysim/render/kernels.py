"""Compiled pixel loops of the agent painter (numba): filling parts by rank, truth statistics.

An agent costs the renderer a dozen small polygons and a few counts; done
with one OpenCV call each, the calls' overhead - not the pixels - was most of
a frame with many agents in view. These loops do a whole batch of agents in
one call each. They are plain loops over pixels, compiled once and cached on
disk (``cache=True``), and deterministic (no parallelism, no fast-math).

Conventions: canvas or frame pixels as in ``citysim.render.canvas`` - pixel
(x, y) has its centre at coordinates (x, y); polygon vertices are in fixed
point with ``SUBPIXEL_BITS`` fractional bits (as ``cv2.fillConvexPoly`` takes
them); boxes are (x0, y0, x1, y1) with exclusive ends.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from citysim.render.light import lamp_light

SUBPIXEL_BITS = 4
_ONE = 1 << SUBPIXEL_BITS


@njit(cache=True, nogil=True)
def _fill_convex(out, verts, n, value):  # pragma: no cover - compiled
    """Set every pixel of ``out`` whose centre lies in the convex polygon ``verts[:n]``
    (fixed point, in order; repeated vertices allowed) to ``value``. Pixels on an edge count
    as inside."""
    h, w = out.shape
    y_lo = verts[0, 1]
    y_hi = verts[0, 1]
    for i in range(1, n):
        y_lo = min(y_lo, verts[i, 1])
        y_hi = max(y_hi, verts[i, 1])
    row0 = max(-((-y_lo) // _ONE), 0)  # ceil
    row1 = min(y_hi // _ONE, h - 1)  # floor
    for y in range(row0, row1 + 1):
        yf = y * _ONE
        x_lo = np.inf
        x_hi = -np.inf
        for i in range(n):
            ax, ay = verts[i, 0], verts[i, 1]
            j = i + 1 if i + 1 < n else 0
            bx, by = verts[j, 0], verts[j, 1]
            if ay == by:
                if ay == yf:  # a horizontal edge on this row
                    x_lo = min(x_lo, min(ax, bx))
                    x_hi = max(x_hi, max(ax, bx))
            elif min(ay, by) <= yf <= max(ay, by):
                x = ax + (yf - ay) * (bx - ax) / (by - ay)
                x_lo = min(x_lo, x)
                x_hi = max(x_hi, x)
        if x_lo > x_hi:
            continue
        col0 = max(int(math.ceil(x_lo / _ONE)), 0)
        col1 = min(int(math.floor(x_hi / _ONE)), w - 1)
        for x in range(col0, col1 + 1):
            out[y, x] = value


@njit(cache=True, nogil=True)
def fill_ranks(ranks, polys, n_verts, agent_parts, rois, silhouettes):  # pragma: no cover
    """Fill a batch of agents' parts into ``ranks`` (uint8), far agents first.

    ``polys`` (P, M, 2) int32 fixed-point outlines, each agent's parts together and in
    drawing order, of which ``n_verts[p]`` are used (0: nothing to draw); part p gets rank
    p + 1. ``agent_parts`` (A + 1,) delimits the agents' parts. After each agent's parts,
    ``silhouettes[a]`` is set to its pixels inside its box ``rois[a]``: those with one of its
    ranks, before nearer agents cover any."""
    for a in range(len(agent_parts) - 1):
        p0, p1 = agent_parts[a], agent_parts[a + 1]
        for p in range(p0, p1):
            if n_verts[p] > 0:
                _fill_convex(ranks, polys[p], n_verts[p], p + 1)
        x0, y0, x1, y1 = rois[a, 0], rois[a, 1], rois[a, 2], rois[a, 3]
        first = p0 + 1
        count = 0
        for y in range(y0, y1):
            for x in range(x0, x1):
                if ranks[y, x] >= first:
                    count += 1
        silhouettes[a] = count


@njit(cache=True, nogil=True)
def clear_boxes(img, boxes):  # pragma: no cover - compiled
    """Zero ``img`` inside each of ``boxes`` (N, 4)."""
    for b in range(len(boxes)):
        for y in range(boxes[b, 1], boxes[b, 3]):
            for x in range(boxes[b, 0], boxes[b, 2]):
                img[y, x] = 0


@njit(cache=True, nogil=True)
def label_stats(labels, frame_u, frame_v, shown_at, wanted, rois, out):  # pragma: no cover
    """Ground-truth figures of the agents labelled ``wanted`` in canvas ``labels``.

    Per agent a: ``out[a, 0]`` its visible canvas pixels (``labels`` equal to ``wanted[a]``
    inside its canvas box ``rois[a]``); ``out[a, 1:5]`` the frame box (x0, y0, x1, y1;
    exclusive ends; all 0 if none) of the frame pixels showing it. Frame pixel (x, y) shows
    canvas pixel ``shown_at[y, x]`` (a flat index into ``labels``: the lens remap's nearest
    pixel); ``frame_u``, ``frame_v`` give each canvas pixel's frame position (empty when
    frame == canvas), so only the frame pixels near the canvas pixels found are searched."""
    h, w = labels.shape
    fh, fw = shown_at.shape
    flat = labels.ravel()
    mapped = frame_u.shape[0] > 0
    for a in range(len(wanted)):
        label = wanted[a]
        count = 0
        cx0, cy0, cx1, cy1 = w, h, -1, -1
        for y in range(rois[a, 1], rois[a, 3]):
            for x in range(rois[a, 0], rois[a, 2]):
                if labels[y, x] == label:
                    count += 1
                    cx0 = min(cx0, x)
                    cx1 = max(cx1, x)
                    cy0 = min(cy0, y)
                    cy1 = max(cy1, y)
        out[a, 0] = count
        out[a, 1:5] = 0
        if count == 0:
            continue
        if mapped:
            # the lens bends the canvas box's border into a gently curved one: its extremes
            # lie at corners or edge midpoints; 2-3 px of margin cover the bending and the
            # nearest-pixel rounding
            u_lo, v_lo, u_hi, v_hi = np.inf, np.inf, -np.inf, -np.inf
            for yy in (cy0, (cy0 + cy1) // 2, cy1):
                for xx in (cx0, (cx0 + cx1) // 2, cx1):
                    u_lo = min(u_lo, frame_u[yy, xx])
                    u_hi = max(u_hi, frame_u[yy, xx])
                    v_lo = min(v_lo, frame_v[yy, xx])
                    v_hi = max(v_hi, frame_v[yy, xx])
            fx0 = min(max(int(math.floor(u_lo)) - 2, 0), fw)
            fy0 = min(max(int(math.floor(v_lo)) - 2, 0), fh)
            fx1 = min(max(int(math.ceil(u_hi)) + 3, 0), fw)
            fy1 = min(max(int(math.ceil(v_hi)) + 3, 0), fh)
        else:
            fx0, fy0, fx1, fy1 = cx0, cy0, cx1 + 1, cy1 + 1
        # the box's edges, each found by scanning inward from the search box's side
        by0 = -1
        for y in range(fy0, fy1):
            for x in range(fx0, fx1):
                if flat[shown_at[y, x]] == label:
                    by0 = y
                    break
            if by0 >= 0:
                break
        if by0 < 0:
            continue
        by1 = by0
        for y in range(fy1 - 1, by0, -1):
            for x in range(fx0, fx1):
                if flat[shown_at[y, x]] == label:
                    by1 = y
                    break
            if by1 > by0:
                break
        bx0 = -1
        for x in range(fx0, fx1):
            for y in range(by0, by1 + 1):
                if flat[shown_at[y, x]] == label:
                    bx0 = x
                    break
            if bx0 >= 0:
                break
        bx1 = bx0
        for x in range(fx1 - 1, bx0, -1):
            for y in range(by0, by1 + 1):
                if flat[shown_at[y, x]] == label:
                    bx1 = x
                    break
            if bx1 > bx0:
                break
        out[a, 1] = bx0
        out[a, 2] = by0
        out[a, 3] = bx1 + 1
        out[a, 4] = by1 + 1


@njit(cache=True, nogil=True)
def cut_behind(ranks, depth, rank_dist_m):  # pragma: no cover - compiled
    """Zero the ranks of parts behind a nearer standing surface: where ``depth`` (m) is less
    than the part's distance ``rank_dist_m[rank]`` (0: never cut)."""
    h, w = ranks.shape
    for y in range(h):
        for x in range(w):
            r = ranks[y, x]
            if r != 0 and depth[y, x] < rank_dist_m[r]:
                ranks[y, x] = 0


@njit(cache=True, nogil=True)
def paint_sharp(ranks, radiance, names, img, labels):  # pragma: no cover - compiled
    """Where a rank has a label in ``names``, the pixel takes its ``radiance`` and label."""
    h, w = ranks.shape
    for y in range(h):
        for x in range(w):
            r = ranks[y, x]
            if names[r] != 0:
                img[y, x] = radiance[r]
                labels[y, x] = names[r]


@njit(cache=True, nogil=True)
def rank_layers(ranks, radiance, coverage, buf, second):  # pragma: no cover - compiled
    """Two layers for one smear: ``radiance[rank]`` in rows [0, h) of ``buf``, ``coverage[rank]``
    from row ``second`` on."""
    h, w = ranks.shape
    for y in range(h):
        for x in range(w):
            r = ranks[y, x]
            buf[y, x] = radiance[r]
            buf[second + y, x] = coverage[r]


@njit(cache=True, nogil=True)
def paint_smeared(
    value, coverage, depth, nearest_m, img, labels, label, ranks, names, dx, dy
):  # pragma: no cover - compiled
    """Composite a smeared layer over ``img``: ``img * (1 - coverage) + value``, nothing where
    ``depth`` (m) is less than ``nearest_m`` (a surface nearer than every member). Covered
    pixels (coverage > 1/2) take ``label``, or if it is 0 the label of the member there at
    mid-exposure: ``names`` of ``ranks`` moved by (dx, dy) px."""
    h, w = img.shape
    for y in range(h):
        for x in range(w):
            if depth[y, x] < nearest_m:
                continue
            c = coverage[y, x]
            img[y, x] = img[y, x] - img[y, x] * c + value[y, x]
            if c > 0.5:
                if label != 0:
                    labels[y, x] = label
                else:
                    sy, sx = y - dy, x - dx
                    if 0 <= sy < h and 0 <= sx < w:
                        now = names[ranks[sy, sx]]
                        if now != 0:
                            labels[y, x] = now


@njit(cache=True, nogil=True)
def pose_parts(
    geometry,
    faces,
    owner,
    pose,
    rot,
    pole,
    camera_px,
    table,
    reflectance,
    light,
    lamp_pos,
    lamp_level,
    exposure_s,
    z_near_m,
    min_blur_px,
    canvas_wh,
    cam_pts,
    polys,
    needs_hull,
    radiance,
    part_dist,
    agent_z,
    agent_view,
):  # pragma: no cover - compiled
    """Pose, project and shade every part of a frame's agents in one pass.

    Inputs: ``geometry`` (P, K + 1 + F, 3) each part's K vertices, centre and F face normals
    in its model frame; ``faces`` (P, 1 + F) its outline-table row and face offsets
    (``citysim.render.models.DrawModel``); ``owner`` (P,) its agent; ``pose`` (N, 5) each agent's
    x, y (m), heading (rad), height (m), speed (m/s); ``rot`` (3, 3) world -> camera;
    ``pole`` (3,) camera position (m); ``camera_px`` (fx, fy, cx, cy) on the canvas;
    ``table`` (T, 2**F, K) outline tables (``citysim.render.outline``); ``reflectance`` (P,);
    ``light`` (emitter gain, uniform irradiance, beam exponent; ``AgentLighting.constants``);
    ``lamp_pos`` (L, 3) and ``lamp_level`` (L,) the lit lamps (``citysim.render.light.lamp_light``);
    ``canvas_wh`` (w, h).

    Outputs: ``cam_pts`` (P, K, 3) camera-frame vertices; ``polys`` (P, K, 2) int32 fixed-point
    outlines (the image's convex polygon, from the table by which faces look at the camera);
    ``needs_hull`` (P,) parts without a table entry (the caller takes their hull);
    ``radiance`` (P,) float32; ``part_dist`` (P,) squared distance of the part centre;
    ``agent_z`` (N, 2) nearest and farthest vertex depth; ``agent_view`` (N, 7): distance of the
    body centre (m), image motion over the exposure du, dv (px), canvas box x0, y0, x1, y1
    (exclusive ends, blur margin in; empty when the agent is out of view).
    """
    n_parts, n_vert = cam_pts.shape[0], cam_pts.shape[1]
    n_faces = faces.shape[1] - 1
    n = pose.shape[0]
    fx, fy, cx, cy = camera_px[0], camera_px[1], camera_px[2], camera_px[3]
    w, h = canvas_wh[0], canvas_wh[1]
    to_cam = np.empty((n, 3, 3))
    shift = np.empty((n, 3))
    for a in range(n):
        c, s = math.cos(pose[a, 2]), math.sin(pose[a, 2])
        for i in range(3):
            to_cam[a, i, 0] = c * rot[i, 0] + s * rot[i, 1]
            to_cam[a, i, 1] = c * rot[i, 1] - s * rot[i, 0]
            to_cam[a, i, 2] = rot[i, 2]
            shift[a, i] = (
                rot[i, 0] * (pose[a, 0] - pole[0])
                + rot[i, 1] * (pose[a, 1] - pole[1])
                - pole[2] * rot[i, 2]
            )
        agent_z[a, 0] = np.inf
        agent_z[a, 1] = -np.inf
        agent_view[a, 3] = np.inf
        agent_view[a, 4] = np.inf
        agent_view[a, 5] = -np.inf
        agent_view[a, 6] = -np.inf
    uv = np.empty((n_vert, 2))
    for p in range(n_parts):
        a = owner[p]
        m = to_cam[a]
        for k in range(n_vert + 1):  # the vertices, then the centre
            x, y, z = geometry[p, k, 0], geometry[p, k, 1], geometry[p, k, 2]
            qx = m[0, 0] * x + m[0, 1] * y + m[0, 2] * z + shift[a, 0]
            qy = m[1, 0] * x + m[1, 1] * y + m[1, 2] * z + shift[a, 1]
            qz = m[2, 0] * x + m[2, 1] * y + m[2, 2] * z + shift[a, 2]
            if k < n_vert:
                cam_pts[p, k, 0], cam_pts[p, k, 1], cam_pts[p, k, 2] = qx, qy, qz
                agent_z[a, 0] = min(agent_z[a, 0], qz)
                agent_z[a, 1] = max(agent_z[a, 1], qz)
                zc = max(qz, z_near_m)
                u, v = fx * qx / zc + cx, fy * qy / zc + cy
                uv[k, 0], uv[k, 1] = u, v
                agent_view[a, 3] = min(agent_view[a, 3], u)
                agent_view[a, 4] = min(agent_view[a, 4], v)
                agent_view[a, 5] = max(agent_view[a, 5], u)
                agent_view[a, 6] = max(agent_view[a, 6], v)
            else:  # the centre: distance for the drawing order, light for the shading
                r2 = qx * qx + qy * qy + qz * qz
                part_dist[p] = r2
                cos_axis = max(qz, 0.0) / math.sqrt(max(r2, 1e-12))
                irr = light[0] * cos_axis ** light[2] / max(r2, 0.04) + light[1]
                if len(lamp_level):
                    wx = rot[0, 0] * qx + rot[1, 0] * qy + rot[2, 0] * qz + pole[0]
                    wy = rot[0, 1] * qx + rot[1, 1] * qy + rot[2, 1] * qz + pole[1]
                    wz = rot[0, 2] * qx + rot[1, 2] * qy + rot[2, 2] * qz + pole[2]
                    for lamp in range(len(lamp_level)):
                        irr += lamp_level[lamp] * lamp_light(
                            lamp_pos[lamp, 0] - wx,
                            lamp_pos[lamp, 1] - wy,
                            lamp_pos[lamp, 2] - wz,
                            0.0,
                            0.0,
                            0.0,
                            True,
                        )
                radiance[p] = np.float32(reflectance[p] * irr)
        # which faces look at the camera (at -shift in the rotated model frame) -> outline
        mask = 0
        for f in range(n_faces):
            gx, gy, gz = (
                geometry[p, n_vert + 1 + f, 0],
                geometry[p, n_vert + 1 + f, 1],
                geometry[p, n_vert + 1 + f, 2],
            )
            facing = 0.0  # the face normal in the camera frame . shift
            for i in range(3):
                facing += (m[i, 0] * gx + m[i, 1] * gy + m[i, 2] * gz) * shift[a, i]
            if facing < -faces[p, 1 + f]:
                mask |= 1 << f
        row = int(faces[p, 0])
        hull = row < 0 or table.shape[0] == 0
        if not hull:
            hull = table[row, mask, 0] < 0
        needs_hull[p] = hull
        for k in range(n_vert):
            j = k if hull else table[row, mask, k]
            polys[p, k, 0] = np.int32(round(uv[j, 0] * _ONE))
            polys[p, k, 1] = np.int32(round(uv[j, 1] * _ONE))
    # per agent: the body centre now and an exposure ago (back along its heading), its box
    for a in range(n):
        half_h = 0.5 * pose[a, 3]
        nx = shift[a, 0] + half_h * rot[0, 2]
        ny = shift[a, 1] + half_h * rot[1, 2]
        nz = shift[a, 2] + half_h * rot[2, 2]
        agent_view[a, 0] = math.sqrt(nx * nx + ny * ny + nz * nz)
        back = exposure_s * pose[a, 4]
        px = nx - back * to_cam[a, 0, 0]
        py = ny - back * to_cam[a, 1, 0]
        pz = nz - back * to_cam[a, 2, 0]
        du = dv = 0.0
        if back > 0.0 and nz >= z_near_m and pz >= z_near_m:
            du = fx * (px / pz - nx / nz)
            dv = fy * (py / pz - ny / nz)
        agent_view[a, 1], agent_view[a, 2] = du, dv
        agent_view[a, 3:7] = agent_box(agent_view[a, 3:7], du, dv, min_blur_px, w, h)


@njit(cache=True, nogil=True)
def agent_box(bounds, du, dv, min_blur_px, w, h):  # pragma: no cover - compiled
    """An agent's canvas box (x0, y0, x1, y1; exclusive ends; clipped to the w x h canvas)
    from the float bounds (u min, v min, u max, v max) of its image, with a margin for its
    smear by the image motion (du, dv) px."""
    pad = 1
    if math.hypot(du, dv) >= min_blur_px:
        pad = int(math.ceil(max(abs(du), abs(dv)))) + 2
    out = np.empty(4)
    out[0] = min(max(math.floor(max(bounds[0], -1e6)) - pad, 0), w)
    out[1] = min(max(math.floor(max(bounds[1], -1e6)) - pad, 0), h)
    out[2] = max(min(math.ceil(min(bounds[2], 1e6)) + pad + 1, w), 0)
    out[3] = max(min(math.ceil(min(bounds[3], 1e6)) + pad + 1, h), 0)
    return out


@njit(cache=True, nogil=True)
def add_spots(coarse, cell_ground, ground_to_cell, spots, touched):  # pragma: no cover
    """Add carried-light spots to the ground irradiance on a coarse grid of cells.

    ``cell_ground`` (ch, cw, 2): the ground point (m) each cell centre sees (NaN: no ground);
    ``ground_to_cell`` (3, 3): ground (x, y, 1) -> cell (col, row) homogeneous;
    ``spots`` (N, 11): per spot its origin x, y (m; the lamps' mean position), heading cos,
    sin, forward reach and half width of its ground box (m), and its beam's peak
    irradiance, centre ahead (m), forward sigma (m), lateral sigma (m), lateral spread per
    metre ahead (``citysim.render.spots`` gives the formula). ``touched`` (4,) gets the cells box
    (x0, y0, x1, y1; exclusive ends) that received light."""
    ch, cw = coarse.shape
    touched[0], touched[1], touched[2], touched[3] = cw, ch, 0, 0
    for a in range(spots.shape[0]):
        ox, oy, c, s, f_far, half_w = (
            spots[a, 0],
            spots[a, 1],
            spots[a, 2],
            spots[a, 3],
            spots[a, 4],
            spots[a, 5],
        )
        peak, centre, sigma_f, sigma_l, spread = (
            spots[a, 6],
            spots[a, 7],
            spots[a, 8],
            spots[a, 9],
            spots[a, 10],
        )
        # the cells the ground box covers: its corners' images when all lie ahead of the camera
        x0, y0, x1, y1 = cw, ch, 0, 0
        ahead = True
        for f in (0.0, f_far):
            for lat in (-half_w, half_w):
                gx, gy = ox + f * c - lat * s, oy + f * s + lat * c
                q = ground_to_cell[2, 0] * gx + ground_to_cell[2, 1] * gy + ground_to_cell[2, 2]
                if q <= 1e-9:
                    ahead = False
                    break
                u = (
                    ground_to_cell[0, 0] * gx + ground_to_cell[0, 1] * gy + ground_to_cell[0, 2]
                ) / q
                v = (
                    ground_to_cell[1, 0] * gx + ground_to_cell[1, 1] * gy + ground_to_cell[1, 2]
                ) / q
                x0 = min(x0, max(int(math.floor(u)) - 1, 0))
                y0 = min(y0, max(int(math.floor(v)) - 1, 0))
                x1 = max(x1, min(int(math.ceil(u)) + 2, cw))
                y1 = max(y1, min(int(math.ceil(v)) + 2, ch))
        if not ahead:  # part of the box lies behind the camera: search every cell
            x0, y0, x1, y1 = 0, 0, cw, ch
        for i in range(y0, y1):
            for j in range(x0, x1):
                dx = cell_ground[i, j, 0] - ox
                dy = cell_ground[i, j, 1] - oy
                f = dx * c + dy * s
                if not (0.0 <= f <= f_far):  # also false for NaN: no ground
                    continue
                lat = dy * c - dx * s
                if abs(lat) > half_w:
                    continue
                width = sigma_l + spread * f
                t = (f - centre) / sigma_f
                r = lat / width
                coarse[i, j] += peak * math.exp(-t * t - r * r) * min(f / 0.5, 1.0)
                touched[0] = min(touched[0], j)
                touched[1] = min(touched[1], i)
                touched[2] = max(touched[2], j + 1)
                touched[3] = max(touched[3], i + 1)


@njit(cache=True, nogil=True)
def group_boxes(
    boxes, motion, slack_px, shared_px, shared_fraction, cluster_of, joint
):  # pragma: no cover
    """Greedy grouping of boxes (N, 4; x0, y0, x1, y1) in order: each joins the first group
    whose joint box grows by at most its own area + ``slack_px`` pixels and whose mean image
    motion (``motion`` (N, 2), px) is within ``shared_px`` px or ``shared_fraction`` of the
    longer motion of its own; otherwise it starts a group. ``cluster_of`` (N,) gets each box's
    group, ``joint`` (N, 6) each group's box and motion sum; returns the number of groups."""
    k = 0
    members = np.zeros(boxes.shape[0], np.int64)
    for i in range(boxes.shape[0]):
        ax0, ay0, ax1, ay1 = boxes[i, 0], boxes[i, 1], boxes[i, 2], boxes[i, 3]
        room = (ax1 - ax0) * (ay1 - ay0) + slack_px
        mu, mv = motion[i, 0], motion[i, 1]
        found = -1
        for c in range(k):
            cx0, cy0, cx1, cy1 = joint[c, 0], joint[c, 1], joint[c, 2], joint[c, 3]
            x0, y0, x1, y1 = min(ax0, cx0), min(ay0, cy0), max(ax1, cx1), max(ay1, cy1)
            if (x1 - x0) * (y1 - y0) > (cx1 - cx0) * (cy1 - cy0) + room:
                continue
            gu, gv = joint[c, 4] / members[c], joint[c, 5] / members[c]
            diff = math.hypot(gu - mu, gv - mv)
            longer = max(math.hypot(gu, gv), math.hypot(mu, mv))
            if diff <= max(shared_px, shared_fraction * longer):
                joint[c, 0], joint[c, 1], joint[c, 2], joint[c, 3] = x0, y0, x1, y1
                joint[c, 4] += mu
                joint[c, 5] += mv
                found = c
                break
        if found < 0:
            found = k
            joint[k, 0], joint[k, 1], joint[k, 2], joint[k, 3] = ax0, ay0, ax1, ay1
            joint[k, 4], joint[k, 5] = mu, mv
            k += 1
        cluster_of[i] = found
        members[found] += 1
    return k


@njit(cache=True, nogil=True)
def merge_box_list(boxes, cost_px):  # pragma: no cover - compiled
    """Boxes (N, 4; x0, y0, x1, y1) joined where their joint box holds at most ``cost_px``
    more pixels than the two apart, repeatedly; empty boxes dropped. Returns (M, 4)."""
    out = np.empty_like(boxes)
    m = 0
    for i in range(boxes.shape[0]):
        bx0, by0, bx1, by1 = boxes[i, 0], boxes[i, 1], boxes[i, 2], boxes[i, 3]
        if bx1 <= bx0 or by1 <= by0:
            continue
        room = (bx1 - bx0) * (by1 - by0) + cost_px
        joined = True
        while joined:  # a grown box may now reach others: keep joining
            joined = False
            for k in range(m):
                x0, y0, x1, y1 = out[k, 0], out[k, 1], out[k, 2], out[k, 3]
                jx0, jy0, jx1, jy1 = min(x0, bx0), min(y0, by0), max(x1, bx1), max(y1, by1)
                if (jx1 - jx0) * (jy1 - jy0) <= (x1 - x0) * (y1 - y0) + room:
                    out[k : m - 1] = out[k + 1 : m].copy()
                    m -= 1
                    bx0, by0, bx1, by1 = jx0, jy0, jx1, jy1
                    room = (bx1 - bx0) * (by1 - by0) + cost_px
                    joined = True
                    break
        out[m, 0], out[m, 1], out[m, 2], out[m, 3] = bx0, by0, bx1, by1
        m += 1
    return out[:m]


@njit(cache=True, nogil=True)
def line_kernel(du_px, dv_px):  # pragma: no cover - compiled
    """The motion-blur line kernel for ``cv2.filter2D`` and its anchor (x, y): the layer
    averaged over its positions from now (offset 0) back to (du, dv) px ago, each sample
    splatted bilinearly; the kernel spans only the line's bounding box."""
    # dst(p) = sum_o k(anchor + o) src(p + o): the layer seen s of the exposure ago sits at
    # +s*d, so pixel p sees the source at p - s*d: weight at offset o = -s*d
    n = int(math.ceil(2.0 * math.hypot(du_px, dv_px))) + 2
    ox_lo, oy_lo = min(-du_px, 0.0), min(-dv_px, 0.0)
    ox_hi, oy_hi = max(-du_px, 0.0), max(-dv_px, 0.0)
    ax, ay = -math.floor(ox_lo), -math.floor(oy_lo)
    width = int(ax + math.floor(ox_hi)) + 2
    height = int(ay + math.floor(oy_hi)) + 2
    kernel = np.zeros((height, width))
    for i in range(n):
        s = i / (n - 1)
        x, y = -s * du_px + ax, -s * dv_px + ay
        x0, y0 = int(math.floor(x)), int(math.floor(y))
        fx, fy = x - x0, y - y0
        kernel[y0, x0] += (1 - fx) * (1 - fy)
        kernel[y0, x0 + 1] += fx * (1 - fy)
        kernel[y0 + 1, x0] += (1 - fx) * fy
        kernel[y0 + 1, x0 + 1] += fx * fy
    return (kernel / kernel.sum()).astype(np.float32), int(ax), int(ay)
