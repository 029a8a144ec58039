"""The optimised mesh generation gives exactly the meshes of the first, straightforward implementation.

``core.mesh.triangulate``/``core.mesh.ruling``/``core.mesh.earcut``/``core.mesh.build`` were rewritten for speed and
checked array by array against a frozen copy of the first implementation; the digests of that implementation's results
are stored in ``tests/data/mesh_digests.json`` (see :mod:`tests.mesh_digests`). These tests recompute them from the
current code on every fixture and example, on hand-made cases with cocircular ties and holes, and on random polygons
for ear clipping.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from curved_fold.core.mesh.build import build_mesh
from curved_fold.core.mesh.earcut import ear_clip
from curved_fold.core.mesh.ruling import EndpointScorer
from curved_fold.core.mesh.triangulate import _incircle_scalar, incircle
from tests import mesh_digests as md
from tests.analytic import bisector_case

RECORDED = json.loads(md.DIGESTS.read_text())
INPUTS = md.input_files()


@pytest.mark.slow
@pytest.mark.parametrize("path", INPUTS, ids=[p.name for p in INPUTS])
def test_same_meshes_as_reference_on_inputs(path) -> None:
    from curved_fold.core.io.reader import read_pattern

    recorded = RECORDED["inputs"].get(path.name)
    assert recorded is not None, f"{path.name}: no recorded digest; regenerate tests/data/mesh_digests.json"
    pat = read_pattern(path)
    assert md.pattern_digest(pat) == recorded["pattern"], (
        f"{path.name}: the discretised pattern changed since the digests were recorded (core.discretize/core.io.svg), "
        "so the mesh digests no longer apply; check the change and regenerate them (tests/mesh_digests.py)"
    )
    for backend in md.BACKENDS:
        for mesh_type in md.MESH_TYPES:
            got = md.mesh_digest(build_mesh(pat, mesh_type, backend))
            assert got == recorded[f"{mesh_type}/{backend}"], f"{path.name} {mesh_type} ({backend}) differs"


@pytest.mark.parametrize("name", sorted(md.hand_made_cases()))
def test_same_meshes_as_reference_on_ties_and_holes(name: str) -> None:
    pat = md.hand_made_cases()[name]()
    for backend in md.BACKENDS:
        for mesh_type in md.MESH_TYPES:
            got = md.mesh_digest(build_mesh(pat, mesh_type, backend))
            assert got == RECORDED["hand_made"][name][f"{mesh_type}/{backend}"], f"{name} {mesh_type} ({backend})"


def test_ear_clip_same_as_reference_on_random_star_polygons() -> None:
    """Star-shaped polygons with many reflex corners and collinear runs: the same triangles, in the same order."""
    for trial, pts in md.star_polygons():
        got = md.array_digest(ear_clip(pts, np.arange(len(pts))).astype(np.int64))
        assert got == RECORDED["ear_clip"][str(trial)], f"trial {trial}"


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
