"""The warm start of a live re-fold after an edit that re-meshes the pattern (core/mesh/transfer.py)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core import run_to_end
from curved_fold.core.io.reader import read_pattern
from curved_fold.core.mesh import transfer
from curved_fold.core.mesh.build import build_mesh
from curved_fold.core.mesh.transfer import IN_PLACE_SHARE, carried_shape, creases_in_place
from curved_fold.core.solve.solver import Solver

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"


@pytest.fixture(scope="module")
def pleats():
    """``examples/curved_pleats.svg`` meshed and folded at 100 %."""
    mesh = build_mesh(read_pattern(EXAMPLES / "curved_pleats.svg"))
    return mesh, Solver(mesh).solve(1.0).positions


def _turned(mesh, degrees: float):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    centre = mesh.vertices.mean(axis=0)
    return replace(mesh, vertices=(mesh.vertices - centre) @ np.array([[c, s], [-s, c]]) + centre)


def test_the_same_pattern_keeps_its_shape(pleats) -> None:
    mesh, positions = pleats
    assert creases_in_place(mesh, mesh) == 1.0
    np.testing.assert_allclose(carried_shape(mesh, positions, mesh), positions, atol=1e-9)


def test_the_carried_shape_comes_in_units_of_bounded_work(pleats, monkeypatch) -> None:
    """A live re-fold runs the carried shape one unit per slice: each unit measures at most ``UNIT_PAIRS`` pairs
    (in one call it took 194–265 ms on a 3,000-face pleat, the longest slice of its live re-fold), and the units
    give the same shape."""
    mesh, positions = pleats
    whole = carried_shape(mesh, positions, mesh)
    monkeypatch.setattr(transfer, "UNIT_PAIRS", 20 * len(mesh.triangles))
    steps = transfer.carried_shape_steps(mesh, positions, mesh)
    units = 0
    while True:
        try:
            next(steps)
        except StopIteration as done:
            carried = done.value
            break
        units += 1
    assert units >= len(mesh.vertices) // 20  # 20 new vertices per unit against the old triangles, at least
    np.testing.assert_array_equal(carried, whole)
    assert run_to_end(transfer.creases_in_place_steps(mesh, mesh)) == 1.0


def test_a_drawing_turned_or_scaled_as_a_whole_folds_afresh(pleats) -> None:
    """Turned 20° about the sheet's centre or scaled 1.05, no crease stays where the old fold had it: no warm
    start (a warm solve from the shape carried by flat position converged to a mangled sheet, or stalled)."""
    mesh, positions = pleats
    for moved in (_turned(mesh, 20.0), replace(mesh, vertices=mesh.vertices * 1.05)):
        assert creases_in_place(mesh, moved) < 0.1
        assert carried_shape(mesh, positions, moved) is None


def test_one_stroke_of_many_moved_keeps_the_warm_start() -> None:
    """One stroke of huffmanTower's 491 shifted 5 mm (an edit of one curve among many): the others are in place,
    the shape is carried (here the flat sheet's)."""
    mesh = build_mesh(read_pattern(FIXTURES / "huffmanTower.svg"))
    creases = np.isin(mesh.assignments, ("M", "V"))
    first = mesh.edge_polyline[creases][0]
    nodes = np.unique(mesh.edges[creases & (mesh.edge_polyline == first)])
    vertices = mesh.vertices.copy()
    vertices[nodes, 0] += 5.0
    moved = replace(mesh, vertices=vertices)
    assert IN_PLACE_SHARE <= creases_in_place(mesh, moved) < 1.0
    flat = np.c_[mesh.vertices, np.zeros(mesh.n_vertices)]
    carried = carried_shape(mesh, flat, moved)
    assert carried is not None and carried.shape == flat.shape


def test_creases_whose_angles_changed_are_not_in_place(pleats) -> None:
    """Every crease's fold angle changed (a reviewer's rings, 150° → 175°: warm from the old shape, the live
    re-fold stopped unconverged in its cap, 47 mm from Re-fold's): not in place, fold afresh. One stroke of five
    moved is not a small edit either (80 % in place)."""
    mesh, positions = pleats
    creases = np.isin(mesh.assignments, ("M", "V"))
    angles = mesh.fold_angles.copy()
    angles[creases] *= 175.0 / 150.0
    assert creases_in_place(mesh, replace(mesh, fold_angles=angles)) == 0.0
    assert carried_shape(mesh, positions, replace(mesh, fold_angles=angles)) is None
    first = mesh.edge_polyline[creases][0]
    vertices = mesh.vertices.copy()
    vertices[np.unique(mesh.edges[creases & (mesh.edge_polyline == first)]), 0] += 1.0
    assert creases_in_place(mesh, replace(mesh, vertices=vertices)) < IN_PLACE_SHARE
