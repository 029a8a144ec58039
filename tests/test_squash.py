"""Squash flips (core.mesh.squash, issue 12 "no kinks"): the measure, the flips, and the pattern they made fold."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import curved_fold.core.mesh.ruling as ruling
from curved_fold.core.io.reader import read_pattern
from curved_fold.core.mesh.build import build_mesh
from curved_fold.core.mesh.squash import SQUASH_STRAIN, squash_strain, squash_strains
from curved_fold.core.pipeline import fold_pattern

PLEATS_CROSSING_A_CURVE_SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="200mm"
 viewBox="0 0 200 200">
<rect x="0" y="0" width="200" height="200" fill="none" stroke="#000000"/>
<path d="M 25 0 L 25 200" fill="none" stroke="#0000ff" opacity="0.2222"/>
<path d="M 50 0 L 50 200" fill="none" stroke="#ff0000" opacity="0.2222"/>
<path d="M 75 0 L 75 200" fill="none" stroke="#0000ff" opacity="0.2222"/>
<path d="M 100 0 L 100 200" fill="none" stroke="#ff0000" opacity="0.2222"/>
<path d="M 125 0 L 125 200" fill="none" stroke="#0000ff" opacity="0.2222"/>
<path d="M 150 0 L 150 200" fill="none" stroke="#ff0000" opacity="0.2222"/>
<path d="M 175 0 L 175 200" fill="none" stroke="#0000ff" opacity="0.2222"/>
<path d="M 0 100 C 60 40 140 160 200 100" fill="none" stroke="#0000ff" opacity="0.3889"/>
</svg>"""
"""Seven straight pleats (40°) crossed by an S-curve valley (70°), a designer's pattern: at 1 mm the CDT fills the
curve's concave sides with fans of caps (middle corners up to 179.1°)."""


@pytest.fixture(scope="module")
def pleats_pattern(tmp_path_factory: pytest.TempPathFactory):
    svg = tmp_path_factory.mktemp("squash") / "pleats_crossing_a_curve.svg"
    svg.write_text(PLEATS_CROSSING_A_CURVE_SVG)
    return read_pattern(svg, interval=1.0)


@pytest.fixture(scope="module")
def pleats_whole(pleats_pattern):
    """The pleats meshed with every straight crease whole (an infinite interval, as before the needle split of
    ``core.mesh.needles``, which puts vertices on the pleats and so removes most caps): the caps these tests are
    about stay."""
    return replace(pleats_pattern, interval=math.inf)


def test_squash_strain_is_second_order_for_caps_and_first_order_for_needles() -> None:
    assert squash_strain([0, 0], [1, 0], [0.5, math.sqrt(3) / 2]) == pytest.approx(1.0)
    for delta_deg in (0.5, 2.0, 5.0):  # isosceles cap, corner 180° − δ: ≈ δ²/8
        h = math.tan(math.radians(delta_deg / 2))
        assert squash_strain([-1, 0], [1, 0], [0, h]) == pytest.approx(math.radians(delta_deg) ** 2 / 8, rel=1e-3)
    for alpha_deg in (0.1, 1.0, 3.0):  # right-angled needle, corner α: cos α + sin α − 1 ≈ sin α
        a = math.radians(alpha_deg)
        s = squash_strain([0, 0], [1, 0], [1, math.tan(a)])
        assert s == pytest.approx(math.cos(a) + math.sin(a) - 1.0, rel=1e-9)
        assert s == pytest.approx(math.sin(a), rel=0.03)


def test_squash_strains_are_the_scalar_values_to_the_bit() -> None:
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(300, 2)) * 10.0
    tris = rng.integers(0, 300, size=(500, 3))
    tris = tris[(tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])]
    batch = squash_strains(pts, tris)
    xy = pts.tolist()
    scalar = [squash_strain(*(xy[i] for i in t)) for t in tris.tolist()]
    assert batch.tolist() == scalar


def test_flips_remove_the_caps_a_far_vertex_can_replace(pleats_whole, monkeypatch: pytest.MonkeyPatch) -> None:
    """With the flips off the mesh has 40 triangles below SQUASH_STRAIN, down to 2.9e-5 (a 179.1° cap); with them
    none, every pattern segment still an edge, the triangles still counter-clockwise and tiling the same area."""
    mesh = build_mesh(pleats_whole)
    monkeypatch.setattr(ruling, "SQUASH_STRAIN", 0.0)
    plain = build_mesh(pleats_whole)
    before, after = squash_strains(plain.vertices, plain.triangles), squash_strains(mesh.vertices, mesh.triangles)
    assert before.min() < 1e-4 and np.count_nonzero(before < SQUASH_STRAIN) >= 20
    assert after.min() >= SQUASH_STRAIN
    assert mesh.swaps > plain.swaps
    assert np.all(mesh.signed_areas() > 0)
    assert mesh.signed_areas().sum() == pytest.approx(plain.signed_areas().sum(), rel=1e-12)
    creases = mesh.assignments != "F"
    assert {tuple(e) for e in mesh.edges[creases].tolist()} == {
        tuple(e) for e in plain.edges[plain.assignments != "F"].tolist()
    }


def test_flips_leave_meshes_without_caps_alone() -> None:
    """CircularPleat-antiFacet, Carved_Cylinder, Treble_Clef, Rotating_Star: no triangle below the threshold, so the
    same meshes as without the flips."""
    root = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"
    for name in ("CircularPleat-antiFacet", "Carved_Cylinder", "Treble_Clef", "Rotating_Star"):
        mesh = build_mesh(read_pattern(root / f"{name}.svg"))
        assert squash_strains(mesh.vertices, mesh.triangles).min() >= SQUASH_STRAIN, name


@pytest.mark.parametrize("percent", [0.6, 1.0])
def test_pleats_crossing_a_curve_fold_at_1mm(pleats_pattern, percent: float) -> None:
    """At 100 % this stopped at the 200-iteration cap at residual 1.6e-4 after 7 s (the fold pressed the 179.1° cap
    flat and through; its fold angle then turned by 0.018 rad per 1e-10 mm). With the caps flipped away: a converged
    stable minimum in ~21 iterations."""
    run = fold_pattern(pleats_pattern, percent=percent)
    report = run.report
    assert report["converged"] and report["negative_pivots"] == 0, report["message"]
    assert report["iterations"] <= 60


def test_pleats_crossing_a_curve_fold_even_with_their_caps(pleats_whole, monkeypatch: pytest.MonkeyPatch) -> None:
    """With the squash flips off the caps stay and the fold presses one flat; the C² fading of its hinges
    (``forces.flat_attenuation``) keeps Newton's model valid there: a converged minimum (43 iterations; with the C¹
    fading 500 iterations, residual 2e-4)."""
    monkeypatch.setattr(ruling, "SQUASH_STRAIN", 0.0)
    run = fold_pattern(pleats_whole, percent=1.0)
    assert squash_strains(run.mesh.vertices, run.mesh.triangles).min() < 1e-4
    assert run.report["converged"] and run.report["negative_pivots"] == 0, run.report["message"]
