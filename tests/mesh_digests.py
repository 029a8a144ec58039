"""Digests of the meshes the first, straightforward mesh code produced, to pin the optimised code to them.

``core.mesh.triangulate``/``core.mesh.ruling``/``core.mesh.earcut`` were rewritten for speed (array half-edges,
vectorised region and face-loop finding, a heap over array-evaluated swap candidates, cached ear tests) and checked
array by array against a frozen copy of the first implementation (commit 7b169e4). Instead of keeping that copy, the
digests of its results are stored in ``tests/data/mesh_digests.json``; ``tests/test_mesh_reference.py`` recomputes
them from the current code. A digest covers every array of the mesh (triangles as a set with their winding, edges,
assignments, fold angles, curve flags, polylines, faces as cycles, swap count), so any change of result shows.

The digests hold on numpy 1.26 and 2.x and on any x86-64 CPU because mesh generation uses only correctly rounded
arithmetic and libm's atan2, never numpy's ``power``/``arctan2`` (docs/packaging.md, "Same meshes on numpy 1.26 and
numpy 2"); they were re-recorded once for that change (the earlier ones held only on AVX-512 CPUs with numpy 1.26).

Regenerate (only after a deliberate change of results, saying why in the commit):
``.venv/bin/python -m curved_fold.tests.mesh_digests --write``.
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FIXTURES = REPO / "tests" / "fixtures" / "origami-simulator"
DIGESTS = Path(__file__).resolve().parent / "data" / "mesh_digests.json"
BACKENDS = ("triangle", "mathutils")
MESH_TYPES = ("earcut", "cdt", "ruling")


def _canonical_rows(tris: np.ndarray, tface: np.ndarray) -> np.ndarray:
    """Rows (triangle rotated to start at its smallest index, face), sorted: the triangles as a set, winding kept."""
    k = np.argmin(tris, axis=1)
    rot = np.take_along_axis(tris, (k[:, None] + np.arange(3)[None, :]) % 3, axis=1)
    rows = np.column_stack([rot, tface]).astype(np.int64)
    return rows[np.lexsort(rows.T[::-1])]


def _canonical_loop(loop: np.ndarray) -> list[int]:
    """The lexicographically smallest rotation of a closed loop."""
    seq = [int(v) for v in loop]
    return min(seq[k:] + seq[:k] for k in range(len(seq))) if seq else []


def array_digest(*arrays: np.ndarray) -> str:
    """SHA-256 over the arrays' dtypes, shapes and bytes (nan-safe: float arrays hashed as they are stored)."""
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def pattern_digest(pattern) -> str:
    """Digest of a crease pattern's arrays: tells whether the mesh code got the same input as when recorded."""
    return array_digest(
        pattern.vertices, pattern.edges, pattern.assignments.astype("<U1"), pattern.fold_angles, pattern.edge_from_curve
    )


def mesh_digest(mesh) -> str:
    """Digest of every array of a FoldMesh, triangle order and face-loop rotation aside."""
    faces = json.dumps([_canonical_loop(f) for f in mesh.faces]).encode()
    return array_digest(
        mesh.vertices,
        _canonical_rows(mesh.triangles, mesh.triangle_face),
        mesh.edges,
        mesh.assignments.astype("<U1"),
        mesh.fold_angles,
        mesh.edge_from_curve,
        mesh.edge_polyline,
        np.frombuffer(faces, dtype=np.uint8),
        np.array([mesh.swaps], dtype=np.int64),
    )


def star_polygons(trials: int = 30) -> Iterator[tuple[int, np.ndarray]]:
    """Star-shaped polygons with many reflex corners, some corners on a circle and collinear runs (fixed seed)."""
    rng = np.random.default_rng(7)
    for trial in range(trials):
        n = int(rng.integers(5, 120))
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
        r = rng.uniform(0.3, 1.0, n)
        if trial % 3 == 0:
            r[::4] = 1.0
        pts = np.column_stack([r * np.cos(ang), r * np.sin(ang)]) * 50.0
        if trial % 5 == 0:
            pts = np.concatenate([pts, np.column_stack([np.linspace(60, 0, 7)[1:-1], np.full(5, -60.0)])])
            pts = np.concatenate([pts, [[0.0, -60.0], [60.0, -60.0]]])
            pts = pts[np.argsort(np.arctan2(pts[:, 1], pts[:, 0]))]
        yield trial, pts


def hand_made_cases() -> dict[str, Callable]:
    """Patterns with cocircular ties and holes, built in code (independent of the discretisation)."""
    from .analytic import bisector_case
    from .test_triangulate import _circles_pattern, _grid_pattern, _square_with_hole

    return {
        "grid": _grid_pattern,
        "circles": _circles_pattern,
        "square_with_hole": _square_with_hole,
        "bisector": lambda: bisector_case().pattern,
    }


def input_files() -> list[Path]:
    files = sorted(FIXTURES.glob("*.svg")) if FIXTURES.is_dir() else []
    return files + sorted((REPO / "examples").glob("*.svg"))


def compute() -> dict:
    """Digests of the current code's results on every recorded case."""
    from ..core.io.reader import read_pattern
    from ..core.mesh.build import build_mesh
    from ..core.mesh.earcut import ear_clip

    out: dict = {"hand_made": {}, "inputs": {}, "ear_clip": {}}
    for name, make in hand_made_cases().items():
        pat = make()
        out["hand_made"][name] = {
            f"{mt}/{be}": mesh_digest(build_mesh(pat, mt, be)) for be in BACKENDS for mt in MESH_TYPES
        }
    for path in input_files():
        pat = read_pattern(path)
        entry = {"pattern": pattern_digest(pat)}
        entry.update({f"{mt}/{be}": mesh_digest(build_mesh(pat, mt, be)) for be in BACKENDS for mt in MESH_TYPES})
        out["inputs"][path.name] = entry
    for trial, pts in star_polygons():
        out["ear_clip"][str(trial)] = array_digest(ear_clip(pts, np.arange(len(pts))).astype(np.int64))
    return out


if __name__ == "__main__":
    if "--write" not in sys.argv:
        print(json.dumps(compute(), indent=1))
    else:
        DIGESTS.write_text(json.dumps(compute(), indent=1) + "\n")
        print(f"wrote {DIGESTS}")
