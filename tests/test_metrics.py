"""Metrics (core.metrics) on exact folded shapes: strain, angle defect and fold-angle error vanish, warp angle is
tiny on ruling meshes, and large where the mesh's diagonals are not rulings."""

from __future__ import annotations

import numpy as np
import pytest

from curved_fold.core.mesh.build import build_mesh
from curved_fold.core.metrics import measures as metrics
from curved_fold.core.pattern.model import CreasePattern
from tests.analytic import annular_sector, bisector_case, parabola_strip


def test_fold_angles_sign_convention() -> None:
    # unit square split on its diagonal, folded about it: valley (toward +z) > 0
    verts = [(0, 0), (1, 0), (1, 1), (0, 1)]
    pat = CreasePattern(
        verts,
        [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2)],
        list("BBBBV"),
        [np.nan] * 4 + [90.0],
        [0, 0, 0, 0, 1],
        [False] * 5,
    )
    mesh = build_mesh(pat, "cdt")
    p = mesh.vertices_3d.copy()
    p[1, 2] = p[3, 2] = 0.3  # both wings up: valley
    theta = metrics.fold_angles(mesh, p)
    crease = mesh.assignments == "V"
    assert theta[crease][0] > 0
    p[1, 2] = p[3, 2] = -0.3
    assert metrics.fold_angles(mesh, p)[crease][0] < 0
    assert np.all(np.isnan(metrics.fold_angles(mesh, p)[mesh.assignments == "B"]))


@pytest.mark.parametrize("rho", [120.0, -90.0])
def test_exact_bisector_shape_metrics(rho: float) -> None:
    case = bisector_case(n_segments=96, fold_angle_deg=rho)
    mesh = build_mesh(case.pattern, "ruling")
    s = metrics.summary(mesh, case.folded_positions())
    assert s["strain_max_pct"] < 1e-9
    assert s["angle_defect_max_deg"] < 1e-9
    assert s["fold_angle_error_max_deg"] < 1e-9
    assert s["warp_edges"] >= 2 * 95  # every bisector counted (the quad diagonals stay flat)
    assert s["warp_mean_deg"] < 0.01  # the central-difference tangents make it O(h²), not 0
    # half-way folded: fold-angle error against the scaled target
    half = case.folded_positions(rho / 2)
    assert metrics.summary(mesh, half, percent=0.5)["fold_angle_error_max_deg"] < 1e-9
    assert metrics.summary(mesh, half)["fold_angle_error_mean_deg"] == pytest.approx(abs(rho) / 2)


def test_warp_is_zero_on_the_discrete_cone() -> None:
    sec = annular_sector(40.0, 70.0, 100.0, 90.0, 108.0)
    n = 16
    th = np.radians(-45 + 90 * np.arange(n + 1) / n)
    radii = (40.0, 70.0, 100.0)
    verts = np.array([(r * np.cos(t), r * np.sin(t)) for r in radii for t in th])
    idx = np.arange(3 * (n + 1)).reshape(3, n + 1)
    edges, asg = [], []
    for k, a in ((0, "B"), (1, "V"), (2, "B")):
        edges += [(idx[k, j], idx[k, j + 1]) for j in range(n)]
        asg += [a] * n
    for j in (0, n):
        edges += [(idx[0, j], idx[1, j]), (idx[1, j], idx[2, j])]
        asg += ["B", "B"]
    angles = [108.0 if a == "V" else np.nan for a in asg]
    pat = CreasePattern(verts, edges, asg, angles, [0] * len(edges), [a == "V" for a in asg])
    mesh = build_mesh(pat, "ruling")
    radial = {(int(idx[k, j]), int(idx[k + 1, j])) for k in (0, 1) for j in range(1, n)}
    if not radial <= set(map(tuple, mesh.edges.tolist())):
        pytest.fail("the ruling mesh should contain the radial rungs of the cone")
    # the discrete closed form is exact for radial rungs whatever the quad diagonals; keep only isometric ones
    p = sec.discrete_positions(mesh.vertices, n)
    s = metrics.summary(mesh, p)
    assert s["strain_max_pct"] < 1e-9
    assert s["warp_mean_deg"] < 1e-9
    assert s["angle_defect_max_deg"] < 1e-9


def test_parabola_exact_normals_mesh_has_small_warp_and_cdt_is_worse() -> None:
    strip = parabola_strip(p=60.0, width=20.0, fold_angle_deg=108.0)
    n = 48
    xs = np.linspace(-60, 60, n + 1)
    c = strip.crease_point(xs)
    t = np.column_stack([np.ones_like(xs), xs / strip.p])
    t /= np.linalg.norm(t, axis=1)[:, None]
    n2 = np.column_stack([-t[:, 1], t[:, 0]])
    verts = np.concatenate([c, c + 20 * n2, c - 20 * n2])
    cr = [(i, i + 1) for i in range(n)]
    b = [(n + 1 + i, n + 2 + i) for i in range(n)] + [(2 * n + 2 + i, 2 * n + 3 + i) for i in range(n)]
    b += [(0, n + 1), (0, 2 * n + 2), (n, 2 * n + 1), (n, 3 * n + 2)]
    m = len(cr) + len(b)
    pat = CreasePattern(
        verts,
        cr + b,
        ["V"] * n + ["B"] * len(b),
        [108.0] * n + [np.nan] * len(b),
        [0] * n + [1] * len(b),
        [True] * n + [False] * len(b),
    )
    assert pat.n_edges == m
    mesh = build_mesh(pat, "ruling")
    s = metrics.summary(mesh, strip.exact_positions(mesh.vertices))
    assert s["warp_mean_deg"] < 0.01
    assert s["strain_max_pct"] < 0.02  # chords of a curved surface: O(h²)


def test_strain_and_defect_detect_stretching() -> None:
    case = bisector_case(n_segments=12)
    mesh = build_mesh(case.pattern, "cdt")
    p = case.folded_positions()
    p_stretched = p * np.array([1.01, 1.0, 1.0])
    s = metrics.summary(mesh, p_stretched)
    assert 0.1 < s["strain_mean_pct"] < 1.0
    st = metrics.strain(mesh, p_stretched)
    assert st.shape == (mesh.n_vertices,)
    bumped = p.copy()
    bumped[5, 2] += 1.0  # lift one interior crease vertex: the cone there is no longer developable
    defect = metrics.angle_defect(mesh, bumped)
    assert np.isfinite(defect).sum() == case.n_segments - 1  # only the interior crease vertices are interior
    assert abs(defect[5]) > 1e-2
    assert np.nanmax(np.abs(metrics.angle_defect(mesh, p))) < 1e-9


def test_warp_per_triangle_is_the_mean_of_its_counted_sides() -> None:
    """The display value of each triangle is the plain mean of the warp of those of its sides that are counted."""
    case = bisector_case(n_segments=12)
    mesh = build_mesh(case.pattern, "cdt")
    rng = np.random.default_rng(5)
    pos = case.folded_positions(100.0)[: mesh.n_vertices] + rng.normal(scale=0.3, size=(mesh.n_vertices, 3))
    per_edge = metrics.warp_angles(mesh, pos)
    per_tri = metrics.warp_per_triangle(mesh, pos)
    index = {tuple(e): k for k, e in enumerate(mesh.edges.tolist())}
    assert np.isfinite(per_edge).sum() > 10
    for t, tri in enumerate(mesh.triangles.tolist()):
        sides = [per_edge[index[tuple(sorted((tri[k], tri[(k + 1) % 3])))]] for k in range(3)]
        counted = [w for w in sides if np.isfinite(w)]
        assert per_tri[t] == pytest.approx(np.mean(counted) if counted else 0.0)


def test_fold_angle_error_wraps_at_180_degrees() -> None:
    """A mountain folded to −180.7° measures +179.3° (positions wrap at ±180°); against its −180° target it is 0.7°
    off, not 359.3°."""
    case = bisector_case(n_segments=12, fold_angle_deg=-180.0)
    mesh = build_mesh(case.pattern, "ruling")
    pos = case.folded_positions(-180.7)[: mesh.n_vertices]
    assert np.allclose(metrics.fold_angles(mesh, pos)[mesh.is_crease()], 179.3)
    err = metrics.fold_angle_error(mesh, pos)[mesh.is_crease()]
    assert np.allclose(np.abs(err), 0.7, atol=1e-6)
    assert metrics.summary(mesh, pos)["fold_angle_error_max_deg"] == pytest.approx(0.7, abs=1e-6)


# ------------------------------------------------------------------------------------------------ verdict (Fig. 7)

EXAMPLES = __import__("pathlib").Path(__file__).resolve().parents[1] / "examples"
FIXTURES = __import__("pathlib").Path(__file__).resolve().parent / "fixtures" / "origami-simulator"


def _arc_mesh(name: str):
    from curved_fold.core.io.reader import read_pattern

    return build_mesh(read_pattern(EXAMPLES / name), "ruling")


def test_verdict_on_given_angles_names_flat_and_wrong_way_creases_by_length() -> None:
    """No solver: every crease at its target passes; the middle arc folded the wrong way, then half-flat, is named
    with its length and a point on it (the arcs are centred at (5, −145) mm in the mesh's y-up millimetres)."""
    from curved_fold.core.metrics.verdict import verdict

    mesh = _arc_mesh("concentric_arcs.svg")
    c = mesh.is_crease()
    theta = np.where(c, mesh.fold_angles, 0.0)
    assert verdict(mesh, theta, 1.0)["does_not_fold_as_assigned"] is False
    arc2 = c & (np.array([mesh.sources[p] if p >= 0 else "" for p in mesh.edge_polyline]) == mesh.sources[2])
    assert "arc2" in mesh.sources[2]
    wrong = theta.copy()
    wrong[arc2] *= -1
    v = verdict(mesh, wrong, 1.0)
    assert v["does_not_fold_as_assigned"] is True and len(v["creases_not_folding"]) == 1
    bad = v["creases_not_folding"][0]
    length = np.linalg.norm(np.diff(mesh.vertices[mesh.edges[arc2]], axis=1), axis=2).sum()
    assert bad["wrong_way_mm"] == pytest.approx(length) and bad["flat_mm"] == 0.0
    assert np.hypot(bad["at_mm"][0] - 5.0, bad["at_mm"][1] + 145.0) == pytest.approx(87.5, abs=0.1)
    assert "arc2" in v["does_not_fold_message"] and "fold the wrong way" in v["does_not_fold_message"]
    flat = theta.copy()
    flat[arc2] *= 0.45  # under half its target: stays flat
    v = verdict(mesh, flat, 1.0)
    assert v["creases_not_folding"][0]["flat_mm"] == pytest.approx(length)
    assert "fold less than half" in v["does_not_fold_message"] and "stay flat" not in v["does_not_fold_message"]
    flat[arc2] = theta[arc2] * 0.55  # over half: folded, although the mean error is large
    assert verdict(mesh, flat, 1.0)["does_not_fold_as_assigned"] is False
    # three quarters of it at a fifth, the rest at its target: the message gives the angle of the part that does not
    # fold, since the crease's mean (two fifths) is near half and read as if it folded (a designer session)
    pieces = np.flatnonzero(arc2)
    flat[pieces] = theta[pieces]
    flat[pieces[: 3 * len(pieces) // 4]] *= 0.2
    v = verdict(mesh, flat, 1.0)
    bad = v["creases_not_folding"][0]
    target = bad["target_deg"]
    assert bad["not_folding_angle_deg"] == pytest.approx(0.2 * target, rel=1e-6) and bad["flat_mm"] < length
    assert (
        f"(folded {0.2 * target:.0f}° there, {bad['angle_deg']:.0f}° on average over the crease, for "
        in (v["does_not_fold_message"])
    )


def test_verdict_caps_targets_near_180_degrees() -> None:
    """A crease folded 70° for a 180° target is folded (curved creases cannot reach 180°), 50° is not."""
    from curved_fold.core.metrics.verdict import REACHABLE_DEG, verdict

    mesh = _arc_mesh("concentric_arcs.svg")
    c = mesh.is_crease()
    mesh.fold_angles[c] = np.sign(mesh.fold_angles[c]) * 180.0
    assert REACHABLE_DEG < 180.0
    folded = np.where(c, np.sign(mesh.fold_angles) * 70.0, 0.0)
    assert verdict(mesh, folded, 1.0)["does_not_fold_as_assigned"] is False
    assert verdict(mesh, folded * 50.0 / 70.0, 1.0)["does_not_fold_as_assigned"] is True


def test_isolated_crease_is_flagged_a_crease_dying_out_is_not() -> None:
    from curved_fold.core.metrics.verdict import verdict
    from curved_fold.core.pattern.discretize import discretize
    from curved_fold.core.pattern.model import CreaseCurve, CurveSegment

    c = [(0, 0), (100, 0), (100, 100), (0, 100)]
    square = CreaseCurve([CurveSegment("line", np.array([c[i], c[(i + 1) % 4]], float)) for i in range(4)], "B", None)
    for start, isolated in (((50, 20), True), ((50, 0), False)):
        crease = CreaseCurve([CurveSegment("line", np.array([start, (50, 80)], float))], "V", 90.0, source="c")
        mesh = build_mesh(discretize([square, crease]), "cdt")
        theta = np.where(mesh.is_crease(), 90.0, 0.0)  # folded fully: the angles cannot tell
        v = verdict(mesh, theta, 1.0)
        assert v["does_not_fold_as_assigned"] is isolated
        assert len(v["isolated_creases"]) == int(isolated)
        if isolated:
            assert v["isolated_creases"][0]["at_mm"] == pytest.approx([50.0, 50.0])
            assert "end inside the paper" in v["does_not_fold_message"]


@pytest.mark.parametrize(
    ("path", "flagged"),
    [
        (EXAMPLES / "cannot_fold.svg", True),
        (EXAMPLES / "concentric_arcs.svg", False),
        (FIXTURES / "wavy_pleats.svg", False),
    ],
    ids=["cannot_fold", "concentric_arcs", "wavy_pleats"],
)
def test_verdict_on_solved_patterns(path, flagged: bool) -> None:
    """Solved at 100 %: the all-mountain arcs are flagged, naming the inner arc (it folds 46° of 108°); the same
    arcs alternating are not; nor is ``wavy_pleats``, whose ±180° creases end 33° (mean) short of their targets."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.pipeline import fold_pattern

    report = fold_pattern(read_pattern(path), percent=1.0).report
    assert report["does_not_fold_as_assigned"] is flagged
    if flagged:
        assert "arc1" in report["does_not_fold_message"]
        assert [c["polyline"] for c in report["creases_not_folding"]] == [1]
    else:
        assert report["creases_not_folding"] == [] and "does_not_fold_message" not in report
    if path.name == "wavy_pleats.svg":
        assert report["fold_angle_error_mean_deg"] > 15.0  # the old alarm's threshold: no verdict any more


ALL_PATTERNS = sorted(FIXTURES.glob("*.svg")) + sorted(EXAMPLES.glob("*.svg"))


@pytest.mark.slow
@pytest.mark.parametrize("percent", [0.6, 1.0])
@pytest.mark.parametrize("path", ALL_PATTERNS, ids=[p.name for p in ALL_PATTERNS])
def test_verdict_on_every_fixture_and_example(path, percent: float) -> None:
    """Issue 12 item 4: of every fixture and example, folded at 60 % and 100 %, only ``cannot_fold`` at 100 % does not
    fold as assigned (measured: its inner arc folds 46° of 108°; at 60 % every arc folds over half its target)."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.pipeline import fold_pattern

    report = fold_pattern(read_pattern(path), percent=percent).report
    expected = path.name == "cannot_fold.svg" and percent == 1.0
    assert report["does_not_fold_as_assigned"] is expected, report.get("does_not_fold_message")
    assert report["isolated_creases"] == []


def test_a_good_miura_is_not_flagged_part_way(monkeypatch) -> None:
    """A Miura-ori of nearly square cells (sector angle 78°, a helper's drawing, ``tests/data/miura_78deg.svg``):
    part way its verticals lag the zigzags (tan(ρ_v/2) = cos γ · tan(ρ_z/2): 22–30° of 84° at 60 %) although the
    pattern folds as assigned (clean at 100 %). Below 100 % only creases that barely move (under a tenth of their
    target) count as flat; with the full fold's "half" it was flagged."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.metrics import verdict as verdict_module
    from curved_fold.core.pipeline import fold_pattern

    pattern = read_pattern(FIXTURES.parents[1] / "data" / "miura_78deg.svg")
    for percent in (0.3, 0.6, 1.0):
        report = fold_pattern(pattern, percent=percent).report
        assert report["converged"] and not report["does_not_fold_as_assigned"], (
            percent,
            report.get("does_not_fold_message"),
        )
    monkeypatch.setattr(verdict_module, "PARTIAL_FOLDED_FRACTION", verdict_module.FOLDED_FRACTION)
    assert fold_pattern(pattern, percent=0.6).report["does_not_fold_as_assigned"]


@pytest.mark.parametrize(
    ("name", "flagged"),
    [("miura_shallow_60deg.svg", False), ("curved_miura_shallow_90deg.svg", False), ("miura_all_mountain.svg", True)],
)
def test_creases_a_four_crease_vertex_holds_back_are_not_flat(name: str, flagged: bool, monkeypatch) -> None:
    """Miura grids of 3 mm zigzags with one angle drawn on every crease (a straight one at 60°, a curved one at 90°;
    a helper's study of the verdict): at 100 % their verticals fold 11–35° as the vertex relation ties them to the
    zigzags (tan(ρ_v/2) = cos γ · tan(ρ_z/2)), under half their target, and the pattern was flagged ("35 % of the
    crease length"). A crease held back at a four-crease vertex whose assignment can fold (3–1, the odd crease beside
    a smallest sector) while a crease there folds is not "flat"; the same grid all mountain (4–0 at every vertex)
    is still flagged, at 60 % and 100 %."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.metrics import verdict as verdict_module
    from curved_fold.core.pipeline import fold_pattern

    pattern = read_pattern(FIXTURES.parents[1] / "data" / name)
    for percent in (0.6, 1.0):
        report = fold_pattern(pattern, percent=percent).report
        said = report.get("does_not_fold_message")
        assert report["converged"] and report["does_not_fold_as_assigned"] is flagged, said
    if not flagged:  # judged against the target alone, the lag was an alarm
        monkeypatch.setattr(verdict_module, "_held_back_at_vertices", lambda mesh, edge, *a: np.zeros(len(edge), bool))
        assert fold_pattern(pattern, percent=1.0).report["does_not_fold_as_assigned"]


def test_a_slit_tip_has_no_warp() -> None:
    """At a slit's tip the face-boundary neighbours are the two lips' copies of one flat point: the tangent is the
    gap between them, its plane arbitrary. One 20 mm slit far from the only crease took a sheet's mean warp from
    1.46° to 6.78°, max 89° (a designer session, fifteenth pass); such edges are not counted now."""
    from curved_fold.core.io.svg import parse_svg_text
    from curved_fold.core.pattern.discretize import discretize
    from curved_fold.core.pipeline import fold_pattern

    def warp(extra: str) -> dict:
        svg = (
            '<svg xmlns="http://www.w3.org/2000/svg" width="150mm" height="100mm" viewBox="0 0 150 100">'
            '<rect x="0" y="0" width="150" height="100" fill="none" stroke="#000000"/>'
            '<path d="M0,50 C50,20 100,80 150,50" fill="none" stroke="#0000ff" stroke-opacity="0.6"/>'
            + extra
            + "</svg>"
        )
        return fold_pattern(discretize(parse_svg_text(svg, "s.svg").curves, interval=3.0)).report

    plain, slit = warp(""), warp('<line x1="20" y1="80" x2="40" y2="80" stroke="#00ff00"/>')
    assert slit["converged"] and slit["warp_max_deg"] < 10.0
    assert slit["warp_mean_deg"] == pytest.approx(plain["warp_mean_deg"], abs=0.05)
