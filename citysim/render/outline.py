"""Outlines of convex parts without a convex hull per part and frame.

The silhouette for every combination of face signs is worked out once per solid's topology and
kept in a table; a frame finds every part's outline from its sign bits. Flat parts (wheels) have
one outline; parts that are no clean convex polytope get no table.

Conventions: part vertices in any right-handed frame (the model's local
frame f, l, z); faces are vertex cycles counter-clockwise seen from outside,
normals point outward; an outline lists at most OUTLINE_VERTICES vertex
indices, the last repeated to fill the row.

Design: docs/design/modules.md (Outlines of convex parts)
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

#: Faces kept per part (a box has 6); parts with more get no table.
MAX_FACES = 6
#: Vertices per outline row (a part's 8 vertices at most).
OUTLINE_VERTICES = 8

#: topology (tuple of face cycles, or ("flat", cycle)) -> row in TABLES
_TOPOLOGY_ROWS: dict[tuple, int] = {}
#: (topologies, 2**MAX_FACES, OUTLINE_VERTICES) int64 outline vertex indices, -1 for no outline
_tables: list[np.ndarray] = []
_stacked: np.ndarray | None = None


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis (3): ``np.cross`` without its axis handling, which
    costs more than the product for the small arrays here."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def outline_tables() -> np.ndarray:
    """All topologies' outline tables stacked: (T, 2**MAX_FACES, OUTLINE_VERTICES) int64."""
    global _stacked
    if _stacked is None or len(_stacked) != len(_tables):
        _stacked = np.stack(_tables) if _tables else np.full((0, 1, 1), -1, np.int64)
    return _stacked


Topology = tuple  # ("flat", cycle) or a tuple of face cycles


def part_topology(
    vertices: np.ndarray, hint: Topology | None = None
) -> tuple[int, np.ndarray, np.ndarray, Topology | None]:
    """One convex part's (K, 3) vertices -> (table row or -1; face normals (MAX_FACES, 3),
    outward and unit, zero for unused faces; one vertex index on each face (MAX_FACES,);
    the topology found, or None).

    ``hint``, the topology of a part built the same way, is checked first (a few vector
    operations) and the full search (slow: all vertex triples) only runs if it fails.
    """
    normals = np.zeros((MAX_FACES, 3))
    on_face = np.zeros(MAX_FACES, np.int64)
    pts = np.asarray(vertices, dtype=np.float64)
    size = float(np.ptp(pts, axis=0).max()) if len(pts) else 0.0
    if size <= 0.0 or len(pts) > OUTLINE_VERTICES:
        return -1, normals, on_face, None
    eps = 1e-9 * size
    topology = hint if hint is not None and _holds(pts, hint, eps) else None
    if topology is None:
        # coincident vertices make faces ambiguous
        gaps = np.linalg.norm(pts[:, None] - pts[None, :], axis=-1) + np.eye(len(pts)) * size
        if gaps.min() <= 1e3 * eps:
            return -1, normals, on_face, None
        flat = _flat_cycle(pts, eps)
        if flat is not None:
            topology = ("flat", flat)
        else:
            faces = _faces(pts, eps)
            if faces is None or len(faces) > MAX_FACES:
                return -1, normals, on_face, None
            topology = tuple(c for c, _ in faces)
    if topology[0] != "flat":
        normals[: len(topology)] = _face_normals(pts, topology)
        on_face[: len(topology)] = [c[0] for c in topology]
    return _row(topology), normals, on_face, topology


def _face_normals(pts: np.ndarray, faces: tuple[tuple[int, ...], ...]) -> np.ndarray:
    """Unit normals of ccw faces from their first three corners (no three corners of a
    strictly convex face are collinear)."""
    idx = np.array([c[:3] for c in faces])
    a, b, c = pts[idx[:, 0]], pts[idx[:, 1]], pts[idx[:, 2]]
    n = _cross(b - a, c - b)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def _holds(pts: np.ndarray, topology: Topology, eps: float) -> bool:
    """Whether ``pts`` have this topology: every face flat with all points behind it (and a
    flat part flat, its cycle still convex)."""
    if topology[0] == "flat":
        flat = _flat_cycle(pts, eps)
        return flat is not None and set(flat) == set(topology[1]) and len(flat) == len(pts)
    if max(max(c) for c in topology) >= len(pts):
        return False
    n = _face_normals(pts, topology)
    if not np.all(np.isfinite(n)):
        return False
    tol = 1e3 * eps
    d = (
        np.einsum("fk,pk->fp", n, pts)
        - np.einsum("fk,fk->f", n, pts[[c[0] for c in topology]])[:, None]
    )
    if np.any(d > tol):
        return False
    mine = np.zeros(d.shape, dtype=bool)
    for f, c in enumerate(topology):
        mine[f, list(c)] = True
    # the face's own corners on it, every other vertex strictly behind it
    return bool(np.all(np.abs(d[mine]) <= tol) and np.all(d[~mine] < -tol))


#: Candidate topologies kept per kind of part (e.g. a vehicle's left and right wheels).
MAX_CANDIDATES = 4


def model_topology(
    corners: np.ndarray, candidates: list[list[Topology]]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[Topology | None]]:
    """``part_topology`` for all parts (P, K, 3) of a model at once: (rows (P,), normals
    (P, MAX_FACES, 3), on-face vertices (P, MAX_FACES), topologies). Each part's
    ``candidates`` (topologies of parts built the same way) are checked first, a few vector
    operations per distinct topology; parts that match none get the full search, and their
    topology is added to their candidates."""
    p = len(corners)
    rows = np.full(p, -1, np.int64)
    normals = np.zeros((p, MAX_FACES, 3))
    on_face = np.zeros((p, MAX_FACES), np.int64)
    found: list[Topology | None] = [None] * p
    for r in range(MAX_CANDIDATES):
        by_topology: dict[Topology, list[int]] = {}
        for j in range(p):
            if found[j] is None and r < len(candidates[j]):
                by_topology.setdefault(candidates[j][r], []).append(j)
        for topology, parts in by_topology.items():
            ok, n = _holds_all(corners[parts], topology)
            good = [j for j, g in zip(parts, ok.tolist(), strict=True) if g]
            if not good:
                continue
            rows[good] = _row(topology)
            for j in good:
                found[j] = topology
            if topology[0] != "flat":
                normals[good, : len(topology)] = n[ok]
                on_face[good, : len(topology)] = [c[0] for c in topology]
    for j in range(p):
        if found[j] is None:
            rows[j], normals[j], on_face[j], found[j] = part_topology(corners[j])
            if found[j] is not None and found[j] not in candidates[j]:
                candidates[j].insert(0, found[j])
                del candidates[j][MAX_CANDIDATES:]
    return rows, normals, on_face, found


@dataclass(frozen=True, eq=False)
class KnownTopology:
    """A model's part topologies in array form, to set up further models built the same way
    without checking them: (``setup``)."""

    rows: np.ndarray  # (P,) outline table rows
    corners: np.ndarray  # (P, MAX_FACES, 3) first three corners of each face (0 if unused)
    used: np.ndarray  # (P, MAX_FACES, 1) 1.0 for faces in use

    @classmethod
    def of(cls, topologies: list[Topology | None]) -> KnownTopology:
        p = len(topologies)
        rows = np.full(p, -1, np.int64)
        corners = np.zeros((p, MAX_FACES, 3), np.int64)
        used = np.zeros((p, MAX_FACES, 1))
        for j, topology in enumerate(topologies):
            if topology is None:
                continue
            rows[j] = _row(topology)
            if topology[0] != "flat":
                corners[j, : len(topology)] = [c[:3] for c in topology]
                used[j, : len(topology)] = 1.0
        return cls(rows, corners, used)

    def setup(self, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``model_topology``'s arrays (rows, normals, on-face vertices) for parts (P, K, 3)."""
        p = np.arange(len(vertices))[:, None]
        a, b, c = (vertices[p, self.corners[..., m]] for m in range(3))
        n = _cross(b - a, c - b) * self.used
        norm = np.linalg.norm(n, axis=2, keepdims=True)
        return self.rows, n / np.where(norm > 0.0, norm, 1.0), self.corners[..., 0]


def _holds_all(pts: np.ndarray, topology: Topology) -> tuple[np.ndarray, np.ndarray]:
    """Whether each part (N, K, 3) has this topology (see ``_holds``), vectorised over parts
    and faces: (ok (N,), unit face normals (N, F, 3))."""
    n_parts, k, _ = pts.shape
    cycles = [topology[1]] if topology[0] == "flat" else list(topology)
    normals = np.zeros((n_parts, len(cycles), 3))
    if max(max(c) for c in cycles) >= k or (topology[0] == "flat" and len(cycles[0]) != k):
        return np.zeros(n_parts, dtype=bool), normals
    size = np.ptp(pts, axis=1).max(axis=1)
    tol = 1e-6 * size[:, None, None]
    ok = size > 0.0
    by_length: dict[int, list[int]] = {}
    for f, c in enumerate(cycles):
        by_length.setdefault(len(c), []).append(f)
    for faces in by_length.values():
        idx = np.array([cycles[f] for f in faces])  # (F, m)
        corners = pts[:, idx]  # (N, F, m, 3)
        edges = np.roll(corners, -1, axis=2) - corners
        turns = _cross(edges, np.roll(edges, -1, axis=2))  # along each face's normal
        n = turns.sum(axis=2)
        length = np.linalg.norm(n, axis=2)
        ok &= np.all(length > 0.0, axis=1)
        n = n / np.maximum(length, 1e-300)[..., None]
        normals[:, faces] = n
        ok &= np.all(np.einsum("nfmk,nfk->nfm", turns, n) > 0.0, axis=(1, 2))  # convex, ccw
        d = (
            np.einsum("npk,nfk->nfp", pts, n)
            - np.einsum("nfk,nfk->nf", corners[:, :, 0], n)[..., None]
        )
        mine = np.zeros((len(faces), k), dtype=bool)
        mine[np.repeat(np.arange(len(faces)), idx.shape[1]), idx.ravel()] = True
        ok &= np.all((np.abs(d) <= tol) | ~mine, axis=(1, 2))  # its corners on the face ...
        if topology[0] != "flat":
            ok &= np.all((d < -tol) | mine, axis=(1, 2))  # ... every other vertex behind it
    return ok, normals


def _row(topology: tuple) -> int:
    row = _TOPOLOGY_ROWS.get(topology)
    if row is None:
        table = np.full((2**MAX_FACES, OUTLINE_VERTICES), -1, np.int64)
        if topology[0] == "flat":
            table[:] = _padded(topology[1])
        else:
            for mask in range(1, 2 ** len(topology)):
                cycle = _silhouette(topology, mask)
                if cycle is not None:
                    table[mask] = _padded(cycle)
        row = len(_tables)
        _tables.append(table)
        _TOPOLOGY_ROWS[topology] = row
    return row


def _padded(cycle: tuple[int, ...]) -> list[int]:
    return list(cycle) + [cycle[-1]] * (OUTLINE_VERTICES - len(cycle))


def _plane_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two in-plane unit axes (u, w = n x u): angles from u toward w run counter-clockwise
    seen from the tip of n."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = _cross(n, helper)
    u /= np.linalg.norm(u)
    return u, _cross(n, u)


def _ccw(pts: np.ndarray, idx: list[int], n: np.ndarray, eps: float) -> tuple[int, ...] | None:
    """Indices ``idx`` of coplanar points in counter-clockwise order about normal n, or None
    if one of them is not a corner of their convex polygon."""
    u, w = _plane_basis(n)
    sub = pts[idx]
    c = sub.mean(axis=0)
    ang = np.arctan2((sub - c) @ w, (sub - c) @ u)
    order = [idx[k] for k in np.argsort(ang)]
    start = order.index(min(order))
    order = order[start:] + order[:start]
    # every corner must turn left (a strictly convex polygon)
    ring = pts[order]
    edges = np.roll(ring, -1, axis=0) - ring
    turns = _cross(edges, np.roll(edges, -1, axis=0)) @ n
    if np.any(turns <= eps * np.linalg.norm(edges, axis=1)):
        return None
    return tuple(order)


def _flat_cycle(pts: np.ndarray, eps: float) -> tuple[int, ...] | None:
    """The cyclic order of a flat part's vertices (all coplanar), else None."""
    c = pts.mean(axis=0)
    _, s, vt = np.linalg.svd(pts - c)
    if s[2] > 1e3 * eps or s[1] <= 1e3 * eps:
        return None
    return _ccw(pts, list(range(len(pts))), vt[2], eps)


def _faces(pts: np.ndarray, eps: float) -> list[tuple[tuple[int, ...], np.ndarray]] | None:
    """Faces of the convex hull of ``pts`` as (ccw vertex cycle, outward unit normal), each
    vertex a corner of its face; None when the points do not give such a polytope."""
    # every vertex triple's plane at once: a hull face when all points lie on one side
    tri = np.array(list(itertools.combinations(range(len(pts)), 3)))
    a = pts[tri[:, 0]]
    n = _cross(pts[tri[:, 1]] - a, pts[tri[:, 2]] - a)
    length = np.linalg.norm(n, axis=1)
    planar = length > eps * eps * 1e6
    n = n[planar] / length[planar, None]
    d = np.einsum("tk,tpk->tp", n, pts[None, :, :] - a[planar][:, None, :])
    tol = 1e3 * eps
    below, above = np.all(d <= tol, axis=1), np.all(d >= -tol, axis=1)
    n[above & ~below] *= -1.0
    on = np.abs(d) <= tol
    found: dict[frozenset[int], np.ndarray] = {}
    for t in np.flatnonzero(below | above).tolist():
        found.setdefault(frozenset(np.flatnonzero(on[t]).tolist()), n[t])
    faces = []
    for key, n in found.items():
        cycle = _ccw(pts, sorted(key), n, eps)
        if cycle is None:
            return None
        faces.append((cycle, n))
    faces.sort()
    edges = {(c[j], c[(j + 1) % len(c)]) for c, _ in faces for j in range(len(c))}
    if any((b, a) not in edges for a, b in edges):
        return None  # not a closed surface: faces meet along split edges
    return faces


def _silhouette(faces: tuple[tuple[int, ...], ...], mask: int) -> tuple[int, ...] | None:
    """The outline (vertex cycle) when the faces in bit ``mask`` face the camera."""
    front = [c for f, c in enumerate(faces) if mask >> f & 1]
    front_edges = {(c[j], c[(j + 1) % len(c)]) for c in front for j in range(len(c))}
    boundary = {a: b for a, b in front_edges if (b, a) not in front_edges}
    if not boundary or len(boundary) > OUTLINE_VERTICES:
        return None
    start = next(iter(boundary))
    cycle = [start]
    while True:
        nxt = boundary.get(cycle[-1])
        if nxt is None:
            return None
        if nxt == start:
            break
        if nxt in cycle:
            return None
        cycle.append(nxt)
    if len(cycle) != len(boundary):
        return None  # the front faces do not form one cap
    return tuple(cycle)


def outline_mask_bits() -> np.ndarray:
    """(MAX_FACES,) the bit of each face in a table row index."""
    return 1 << np.arange(MAX_FACES)
