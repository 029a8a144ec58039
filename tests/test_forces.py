"""The bar-and-hinge forces are the exact negative gradient of the energy (central finite differences)."""

from __future__ import annotations

import numpy as np
import pytest

from curved_fold.core.solve import forces as F  # noqa: N812
from curved_fold.core.solve.model import build_model, mesh_from_triangles


def grid_mesh(nx: int = 3, ny: int = 3, size: float = 30.0, creases=None):
    g = np.array([[i, j] for j in range(ny + 1) for i in range(nx + 1)], float) * size / max(nx, ny)
    tris = []
    for j in range(ny):
        for i in range(nx):
            a = j * (nx + 1) + i
            tris += [[a, a + 1, a + nx + 2], [a, a + nx + 2, a + nx + 1]]
    return mesh_from_triangles(g, np.array(tris), creases or {})


def finite_difference_forces(model, x, theta, percent, eps=1e-6):
    fd = np.zeros_like(x)
    for i in range(len(x)):
        for k in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, k] += eps
            xm[i, k] -= eps
            ep = F.evaluate(model, xp, theta, percent, forces=False).energy
            em = F.evaluate(model, xm, theta, percent, forces=False).energy
            fd[i, k] = -(ep - em) / (2 * eps)
    return fd


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_total_force_is_negative_gradient(seed):
    mesh = grid_mesh(creases={(1, 5): ("V", 90.0), (5, 9): ("M", -60.0), (2, 6): ("U", np.nan)})
    model = build_model(mesh)
    rng = np.random.default_rng(seed)
    x = model.rest + rng.normal(0, 0.08, model.rest.shape)
    theta = F.fold_angles(model, x)
    ev = F.evaluate(model, x, theta, 0.7)
    fd = finite_difference_forces(model, x, theta, 0.7)
    assert np.max(np.abs(fd - ev.forces)) < 1e-6 * max(1.0, np.max(np.abs(ev.forces)))
    assert np.allclose(ev.forces.sum(axis=0), 0.0, atol=1e-10)  # internal forces: no net force


def test_hinge_and_face_terms_separately():
    mesh = grid_mesh(2, 1, creases={(1, 4): ("V", 150.0)})
    rng = np.random.default_rng(5)
    for axial, face, panel in ((0.0, 0.0, 0.7), (0.0, 0.2, 0.0)):
        model = build_model(mesh, axial_stiffness=axial, face_stiffness=face, panel_stiffness=panel)
        x = model.rest + rng.normal(0, 0.1, model.rest.shape)
        theta = F.fold_angles(model, x)
        ev = F.evaluate(model, x, theta, 1.0)
        assert np.max(np.abs(ev.forces)) > 1e-3  # the term is active
        fd = finite_difference_forces(model, x, theta, 1.0)
        assert np.max(np.abs(fd - ev.forces)) < 1e-6


def test_fold_angle_sign_valley_positive():
    """Wings lifted towards the normals' side (+z) give θ > 0 (valley), reference §3.4: 34.9° for lift 0.3."""
    verts = np.array([[0, 0], [1, 0], [0.5, 1], [0.5, -1]], float)
    mesh = mesh_from_triangles(verts, np.array([[0, 1, 2], [1, 0, 3]]), {(0, 1): ("V", 90.0)})
    model = build_model(mesh)
    x = np.column_stack([verts, [0, 0, 0.3, 0.3]])
    theta = np.rad2deg(F.fold_angles(model, model.from_mm(x)))
    assert theta[0] == pytest.approx(2 * np.degrees(np.arctan(0.3)), abs=1e-9)
    x[:, 2] *= -1
    assert np.rad2deg(F.fold_angles(model, model.from_mm(x)))[0] < 0


def test_unwrapping_passes_pi():
    verts = np.array([[0, 0], [1, 0], [0.5, 1], [0.5, -1]], float)
    mesh = mesh_from_triangles(verts, np.array([[0, 1, 2], [1, 0, 3]]), {(0, 1): ("V", 90.0)})
    model = build_model(mesh)
    prev = np.zeros(1)
    for deg in np.arange(0, 350, 10.0):
        half = np.radians(deg) / 2
        x = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.cos(half), np.sin(half)], [0.5, -np.cos(half), np.sin(half)]])
        prev = F.fold_angles(model, model.from_mm(x), prev)
        assert np.degrees(prev[0]) == pytest.approx(deg, abs=1e-6)


def test_degenerate_hinge_is_skipped():
    verts = np.array([[0, 0], [1, 0], [0.5, 1], [0.5, -1]], float)
    mesh = mesh_from_triangles(verts, np.array([[0, 1, 2], [1, 0, 3]]), {(0, 1): ("V", 90.0)})
    model = build_model(mesh)
    x = model.rest.copy()
    x[2] = x[0] + 0.5 * (x[1] - x[0])  # wing on the hinge line: h = 0
    ev = F.evaluate(model, x, None, 1.0)
    assert np.all(np.isfinite(ev.forces))
