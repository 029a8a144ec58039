"""The optimised mesh generation gives exactly the meshes of the straightforward reference (tests/mesh_reference).

``core.triangulate``/``core.ruling``/``core.earcut``/``core.meshing`` were rewritten for speed (array half-edges,
vectorised region and face-loop finding, a heap over array-evaluated swap candidates, cached ear tests). These tests
compare every array of the resulting :class:`FoldMesh` — triangles in order, edges, assignments, fold angles, faces,
swap counts — with the frozen copy of the first implementation, on every fixture and example and on hand-made cases
with cocircular ties.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.earcut import ear_clip
from curved_fold.core.meshing import build_mesh
from curved_fold.core.ruling import EndpointScorer
from curved_fold.core.triangulate import _incircle_scalar, constrained_triangulation, incircle
from tests.analytic import bisector_case
from tests.mesh_reference import earcut as ref_earcut
from tests.mesh_reference import meshing as ref_meshing
from tests.mesh_reference import triangulate as ref_triangulate
from tests.test_triangulate import _circles_pattern, _grid_pattern, _square_with_hole

REPO = Path(__file__).resolve().parents[1]
FIXTURES = Path(__file__).resolve().parents[2] / "shared" / "fixtures" / "origami-simulator"
INPUTS = (sorted(FIXTURES.glob("*.svg")) if FIXTURES.is_dir() else []) + sorted((REPO / "examples").glob("*.svg"))


def _canonical_rows(tris: np.ndarray, tface: np.ndarray) -> np.ndarray:
    """Rows (triangle rotated to start at its smallest index, face), sorted: the triangles as a set, winding kept."""
    k = np.argmin(tris, axis=1)
    rot = np.take_along_axis(tris, (k[:, None] + np.arange(3)[None, :]) % 3, axis=1)
    rows = np.column_stack([rot, tface])
    return rows[np.lexsort(rows.T[::-1])]


def _canonical_loop(loop: np.ndarray) -> list[int]:
    """The lexicographically smallest rotation of a closed loop."""
    seq = loop.tolist()
    return min(seq[k:] + seq[:k] for k in range(len(seq)))


def _assert_same_mesh(new, ref, what: str) -> None:
    """Every array equal; for ruling meshes the triangles (and face loops) as sets/cycles: the optimised swaps
    keep each triangle in its CDT slot instead of bmesh's element order, which depends on bmesh's memory pools."""
    if new.mesh_type == "ruling":
        a, b = _canonical_rows(new.triangles, new.triangle_face), _canonical_rows(ref.triangles, ref.triangle_face)
        assert np.array_equal(a, b), f"{what}: triangles differ from the reference"
        for k, (fa, fb) in enumerate(zip(new.faces, ref.faces, strict=True)):
            assert _canonical_loop(fa) == _canonical_loop(fb), f"{what}: face loop {k} differs"
        names: tuple[str, ...] = ("vertices", "edges", "fold_angles", "edge_from_curve", "edge_polyline")
    else:
        names = ("vertices", "triangles", "edges", "fold_angles", "edge_from_curve", "edge_polyline", "triangle_face")
        for k, (fa, fb) in enumerate(zip(new.faces, ref.faces, strict=True)):
            assert np.array_equal(fa, fb), f"{what}: face loop {k} differs"
    for name in names:
        a, b = getattr(new, name), getattr(ref, name)
        assert a.shape == b.shape, f"{what}: {name} shape {a.shape} != reference {b.shape}"
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), f"{what}: {name} differs from the reference"
    assert np.array_equal(new.assignments, ref.assignments), f"{what}: assignments differ"
    assert len(new.faces) == len(ref.faces), f"{what}: number of crease-pattern faces differs"
    assert new.swaps == ref.swaps, f"{what}: {new.swaps} swaps, reference {ref.swaps}"
    assert new.warnings == ref.warnings, f"{what}: warnings differ"


def _assert_same_triangulation(new, ref, what: str) -> None:
    for name in ("vertices", "vertex_source", "triangles", "triangle_region", "face_simple"):
        assert np.array_equal(getattr(new, name), getattr(ref, name)), f"{what}: {name} differs from the reference"
    assert new.segment_of == ref.segment_of, f"{what}: segment map differs"
    assert len(new.face_loops) == len(ref.face_loops)
    for k, (la, lb) in enumerate(zip(new.face_loops, ref.face_loops, strict=True)):
        assert len(la) == len(lb) and all(np.array_equal(x, y) for x, y in zip(la, lb, strict=True)), f"{what}: {k}"
    assert new.warnings == ref.warnings


@pytest.mark.slow
@pytest.mark.skipif(not INPUTS, reason=f"neither fixtures ({FIXTURES}) nor examples found")
@pytest.mark.parametrize("path", INPUTS, ids=[p.name for p in INPUTS])
def test_same_meshes_as_reference_on_inputs(path: Path) -> None:
    reader = pytest.importorskip("curved_fold.core.reader", reason="core.reader (INPUT helper) not available")
    pat = reader.read_pattern(path)
    for backend in ("triangle", "mathutils"):
        _assert_same_triangulation(
            constrained_triangulation(pat, backend),
            ref_triangulate.constrained_triangulation(pat, backend),
            f"{path.name} CDT ({backend})",
        )
    for mesh_type in ("earcut", "cdt", "ruling"):
        new = build_mesh(pat, mesh_type, "triangle")
        ref = ref_meshing.build_mesh(pat, mesh_type, "triangle")
        _assert_same_mesh(new, ref, f"{path.name} {mesh_type}")


@pytest.mark.parametrize("make", [_grid_pattern, _circles_pattern, _square_with_hole, bisector_case])
def test_same_meshes_as_reference_on_ties_and_holes(make) -> None:
    pat = make()
    pat = getattr(pat, "pattern", pat)
    for backend in ("triangle", "mathutils"):
        for mesh_type in ("earcut", "cdt", "ruling"):
            new = build_mesh(pat, mesh_type, backend)
            ref = ref_meshing.build_mesh(pat, mesh_type, backend)
            _assert_same_mesh(new, ref, f"{make.__name__} {mesh_type} ({backend})")


def test_ear_clip_same_as_reference_on_random_star_polygons() -> None:
    """Star-shaped polygons with many reflex corners and collinear runs: the same triangles, in the same order."""
    rng = np.random.default_rng(7)
    for trial in range(30):
        n = int(rng.integers(5, 120))
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
        r = rng.uniform(0.3, 1.0, n)
        if trial % 3 == 0:
            r[::4] = 1.0  # some corners on a circle
        pts = np.column_stack([r * np.cos(ang), r * np.sin(ang)]) * 50.0
        if trial % 5 == 0:  # a straight run of collinear corners
            pts = np.concatenate([pts, np.column_stack([np.linspace(60, 0, 7)[1:-1], np.full(5, -60.0)])])
            pts = np.concatenate([pts, [[0.0, -60.0], [60.0, -60.0]]])
            pts = pts[np.argsort(np.arctan2(pts[:, 1], pts[:, 0]))]
        loop = np.arange(len(pts))
        assert np.array_equal(ear_clip(pts, loop), ref_earcut.ear_clip(pts, loop)), f"trial {trial}"


def test_scalar_incircle_is_bit_identical_to_numpy() -> None:
    """The flip loop's plain-float in-circle must give the numpy function's values exactly (ties are decided on
    them), on random and on nearly cocircular quads at several scales."""
    rng = np.random.default_rng(3)
    for scale in (1e-3, 1.0, 150.0, 1e4):
        th = rng.uniform(0, 2 * np.pi, size=(400, 4))
        ring = np.stack([np.cos(th), np.sin(th)], -1) * scale + rng.normal(size=(400, 1, 2)) * scale
        for quads in (rng.normal(size=(400, 4, 2)) * scale, ring):
            batch = incircle(quads[:, 0], quads[:, 1], quads[:, 2], quads[:, 3])
            single = [_incircle_scalar(*(q[k].tolist() for k in range(4))) for q in quads]
            assert np.array_equal(batch, np.array(single))


def test_batch_swap_costs_equal_scalar_costs() -> None:
    """The vectorised first evaluation of the swap loop scores edges exactly as the per-edge path does."""
    case = bisector_case(n_segments=30, width_left=30.0, width_right=45.0)
    pat = case.pattern
    rng = np.random.default_rng(0)
    pairs = rng.integers(0, pat.n_vertices, size=(3000, 2))
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    batch = EndpointScorer(pat.vertices, pat.edges, pat.edge_from_curve).costs(pairs[:, 0], pairs[:, 1])
    scalar = EndpointScorer(pat.vertices, pat.edges, pat.edge_from_curve)
    single = np.array([scalar.cost(int(p), int(q)) for p, q in pairs])
    assert np.array_equal(batch, single)
    assert np.isfinite(batch).any() and np.isinf(batch).any()
