"""Polylines of a crease pattern: chains of segments through vertices where exactly two meet.

A FOLD file (or a discretised pattern) holds straight segments only; chaining them gives back the polylines a
designer drew — one editable curve per chain of one assignment and angle instead of hundreds of segments — for the
Import operator, the crease-curve display of a folded mesh and the SVG export.
"""

from __future__ import annotations

import numpy as np

from .model import CreaseCurve, CreasePattern, CurveSegment


def chain_edges(edges: np.ndarray) -> list[np.ndarray]:
    """Split an edge set into chains of vertex indices: walks through vertices of degree 2, ends at branch points.

    Open chains start at their ends; what is left are closed loops (first vertex repeated at the end). Used for the
    crease-curve children, the SVG export and reading FOLD files as curves; not on any solver path.
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    adjacency: dict[int, list[int]] = {}
    for k, (a, b) in enumerate(edges.tolist()):
        adjacency.setdefault(a, []).append(k)
        adjacency.setdefault(b, []).append(k)
    used = np.zeros(len(edges), dtype=bool)
    chains: list[np.ndarray] = []

    def walk(start: int, k: int | None) -> np.ndarray:
        chain = [start]
        v = start
        while k is not None and not used[k]:
            used[k] = True
            a, b = edges[k]
            v = int(b if a == v else a)
            chain.append(v)
            nxt = [j for j in adjacency[v] if not used[j]]
            k = nxt[0] if len(adjacency[v]) == 2 and nxt else None
        return np.array(chain, dtype=np.int64)

    for v, ks in adjacency.items():
        if len(ks) != 2:
            for k in ks:
                if not used[k]:
                    chains.append(walk(v, k))
    for k in range(len(edges)):
        if not used[k]:
            chains.append(walk(int(edges[k][0]), k))
    return chains


def curves_from_pattern(pattern: CreasePattern) -> list[CreaseCurve]:
    """Chain the straight segments of a discretised pattern into polyline :class:`CreaseCurve` s.

    Segments are grouped by (assignment, fold angle, source polyline) and chained through vertices of degree 2
    within the group, so a FOLD file's discretised curve comes back as one editable curve, not hundreds. A plain
    FOLD file (every edge its own polyline) is grouped by assignment and angle only.
    """
    angles = np.round(np.nan_to_num(pattern.fold_angles, nan=np.inf), 9)
    poly_ids = pattern.edge_polyline
    if len(np.unique(poly_ids)) == len(poly_ids):  # plain FOLD: one "polyline" per edge carries no grouping
        poly_ids = np.full(len(poly_ids), -1)
    keys = {}
    rows = zip(pattern.assignments.tolist(), angles.tolist(), poly_ids.tolist(), strict=True)
    for i, key in enumerate(rows):
        keys.setdefault(key, []).append(i)
    curves: list[CreaseCurve] = []
    for (assignment, angle, poly), idx in keys.items():
        for chain in chain_edges(pattern.edges[idx]):
            pts = pattern.vertices[chain]
            closed = len(chain) > 2 and chain[0] == chain[-1]
            segs = [CurveSegment("line", np.array([pts[k], pts[k + 1]])) for k in range(len(pts) - 1)]
            src = pattern.sources[poly] if 0 <= poly < len(pattern.sources) else f"FOLD edges {idx[:3]}..."
            curves.append(
                CreaseCurve(
                    segments=segs,
                    assignment=assignment,
                    fold_angle=None if not np.isfinite(angle) else float(angle),
                    closed=bool(closed),
                    source=src,
                )
            )
    return curves
