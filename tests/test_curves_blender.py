"""Crease curves drawn as Blender curve objects (scene/curves.py, scene/properties.py, operators/roles.py).

The key check: the same Bézier creases drawn in Blender and written in an SVG discretise to the same pattern.
Everything runs against the extension installed from its zip (fixtures ``extension`` and ``clean_scene``).
"""

from __future__ import annotations

import importlib
import itertools
import math

import numpy as np
import pytest

from curved_fold.core.io.svg import parse_svg_text
from curved_fold.core.pattern.discretize import discretize
from curved_fold.core.pattern.model import CreaseCurve, CurveSegment

bpy = pytest.importorskip("bpy")

# A 200 × 100 mm sheet (y up, mm). Dyadic coordinates: exact in Blender's float32 when 1 BU = 1 mm.
BORDER = [(0.0, 0.0), (200.0, 0.0), (200.0, 100.0), (0.0, 100.0)]
VALLEY = [  # two cubic segments: knots with (handle_left, co, handle_right)
    ((40.0, 0.0), (50.0, 0.0), (60.0, 25.0)),
    ((70.0, 40.0), (100.0, 50.0), (130.0, 60.0)),
    ((140.0, 75.0), (150.0, 100.0), (160.0, 100.0)),
]
MOUNTAIN = [
    ((10.0, 20.0), (20.0, 0.0), (30.5, 37.25)),
    ((12.5, 70.0), (20.0, 100.0), (30.0, 110.0)),
]


@pytest.fixture
def mod(extension):
    """The installed copy's ``scene.curves`` module."""
    return importlib.import_module(extension.__name__ + ".scene.curves")


def bezier_object(name: str, knots, *, role: str, scale: float = 1.0, cyclic: bool = False, angle: float = 180.0):
    """A curve object with one Bézier spline; ``knots`` = [(handle_left, co, handle_right)] in mm × ``scale`` BU."""
    cu = bpy.data.curves.new(name, "CURVE")
    cu.dimensions = "3D"
    add_bezier_spline(cu, knots, scale=scale, cyclic=cyclic)
    ob = bpy.data.objects.new(name, cu)
    bpy.context.scene.collection.objects.link(ob)
    ob.curved_fold.fold_angle = math.radians(angle)
    ob.curved_fold.role = role
    return ob


def add_bezier_spline(cu, knots, *, scale: float = 1.0, cyclic: bool = False, z: float = 0.0):
    sp = cu.splines.new("BEZIER")
    sp.bezier_points.add(len(knots) - 1)
    for bp, (hl, co, hr) in zip(sp.bezier_points, knots, strict=True):
        bp.handle_left_type = bp.handle_right_type = "FREE"
        bp.co = (co[0] * scale, co[1] * scale, z)
        bp.handle_left = (hl[0] * scale, hl[1] * scale, z)
        bp.handle_right = (hr[0] * scale, hr[1] * scale, z)
    sp.use_cyclic_u = cyclic
    return sp


def poly_object(name: str, points, *, role: str, scale: float = 1.0, cyclic: bool = True):
    cu = bpy.data.curves.new(name, "CURVE")
    sp = cu.splines.new("POLY")
    sp.points.add(len(points) - 1)
    for p, (x, y) in zip(sp.points, points, strict=True):
        p.co = (x * scale, y * scale, 0.0, 1.0)
    sp.use_cyclic_u = cyclic
    ob = bpy.data.objects.new(name, cu)
    bpy.context.scene.collection.objects.link(ob)
    ob.curved_fold.role = role
    return ob


def svg_path(knots, cyclic: bool = False) -> str:
    """SVG path data of the same Bézier chain (SVG y = −y: the reader flips y, with this viewBox 1 unit = 1 mm)."""

    def p(xy):
        return f"{xy[0]!r},{-xy[1]!r}"

    d = [f"M {p(knots[0][1])}"]
    pairs = list(zip(knots[:-1], knots[1:], strict=True)) + ([(knots[-1], knots[0])] if cyclic else [])
    for a, b in pairs:
        d.append(f"C {p(a[2])} {p(b[0])} {p(b[1])}")
    return " ".join(d) + (" Z" if cyclic else "")


def svg_document(paths: list[tuple[str, str]]) -> str:
    body = "\n".join(f'  <path d="{d}" fill="none" stroke="{colour}"/>' for d, colour in paths)
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="100mm" viewBox="0 0 200 100">\n{body}\n</svg>'
    )


def mm_per_bu_one(scene) -> None:
    scene.unit_settings.system = "METRIC"
    scene.unit_settings.scale_length = 0.001  # 1 BU = 1 mm: coordinates stay exact


def assert_same_pattern(a, b, rel: float = 1e-9) -> None:
    assert a.n_vertices == b.n_vertices and a.n_edges == b.n_edges
    scale = max(a.size, 1.0)
    np.testing.assert_allclose(a.vertices, b.vertices, rtol=0, atol=rel * scale)
    np.testing.assert_array_equal(a.edges, b.edges)
    np.testing.assert_array_equal(a.assignments, b.assignments)
    np.testing.assert_array_equal(a.fold_angles, b.fold_angles)
    np.testing.assert_array_equal(a.edge_from_curve, b.edge_from_curve)


def test_blender_curves_discretise_like_the_same_svg(mod, clean_scene):
    mm_per_bu_one(clean_scene)
    border = poly_object("Border", BORDER, role="BORDER")
    valley = bezier_object("Valley", VALLEY, role="VALLEY")
    mountain = bezier_object("Mountain", MOUNTAIN, role="MOUNTAIN", angle=90.0)
    from_blender = mod.curves_from_objects([border, valley, mountain])
    assert [c.source for c in from_blender] == [
        "curve 'Border' spline 0",
        "curve 'Valley' spline 0",
        "curve 'Mountain' spline 0",
    ]
    assert [c.assignment for c in from_blender] == ["B", "V", "M"]
    assert [c.fold_angle for c in from_blender] == [None, 180.0, -90.0]
    assert [s.kind for s in from_blender[1].segments] == ["cubic", "cubic"]

    rect = "M " + " L ".join(f"{x!r},{-y!r}" for x, y in BORDER) + " Z"
    svg = svg_document([(rect, "#000000"), (svg_path(VALLEY), "#0000ff"), (svg_path(MOUNTAIN), "#ff0000")])
    from_svg = parse_svg_text(svg, "test.svg").curves
    from_svg[2].fold_angle = -90.0  # SVG angles come from opacity; full opacity = 180
    for a, b in zip(from_blender, from_svg, strict=True):
        assert len(a.segments) == len(b.segments)
        for sa, sb in zip(a.segments, b.segments, strict=True):
            np.testing.assert_allclose(sa.points, sb.points, rtol=0, atol=1e-9)

    params = {"interval": 5.0, "tolerance": 0.05, "merge_tolerance": 0.01}
    pa = discretize(from_blender, **params)
    pb = discretize(from_svg, **params)
    assert pa.count("V") > 10 and pa.count("M") > 5  # the curves were really subdivided
    assert_same_pattern(pa, pb)


def test_cyclic_bezier_spline_gets_its_closing_segment(mod, clean_scene):
    mm_per_bu_one(clean_scene)
    k = 4.0 / 3.0 * math.tan(math.pi / 8) * 32.0  # circle of radius 32 mm around (100, 50)
    knots = [
        ((132.0, 50.0 - k), (132.0, 50.0), (132.0, 50.0 + k)),
        ((100.0 + k, 82.0), (100.0, 82.0), (100.0 - k, 82.0)),
        ((68.0, 50.0 + k), (68.0, 50.0), (68.0, 50.0 - k)),
        ((100.0 - k, 18.0), (100.0, 18.0), (100.0 + k, 18.0)),
    ]
    ob = bezier_object("Loop", knots, role="VALLEY", cyclic=True)
    (curve,) = mod.curves_from_objects([ob])
    assert curve.closed and len(curve.segments) == 4
    np.testing.assert_allclose(curve.segments[-1].end, curve.segments[0].start, atol=1e-12)
    np.testing.assert_allclose(curve.segments[-1].points[1], knots[3][2], atol=1e-5)
    # The same closed path in SVG discretises identically.
    svg = svg_document([(svg_path(knots, cyclic=True), "#0000ff")])
    (svg_curve,) = parse_svg_text(svg, "loop.svg").curves
    params = {"interval": 4.0, "tolerance": 0.05, "merge_tolerance": 0.01}
    assert_same_pattern(discretize([curve], **params), discretize([svg_curve], **params), rel=1e-6)
    # A Blender-drawn circle is within 0.03 % of the true radius everywhere.
    pts = np.concatenate([s.evaluate(np.linspace(0, 1, 50)) for s in curve.segments])
    radius = np.hypot(pts[:, 0] - 100.0, pts[:, 1] - 50.0)
    assert np.all(np.abs(radius - 32.0) < 32.0 * 3e-4)


def test_world_matrix_is_applied(mod, clean_scene):
    mm_per_bu_one(clean_scene)
    ob = bezier_object("Moved", VALLEY, role="VALLEY")
    ob.location = (12.0, -7.0, 3.0)
    ob.rotation_euler = (0.0, 0.0, math.radians(30.0))
    ob.scale = (2.0, 2.0, 2.0)
    bpy.context.view_layer.update()
    (curve,) = mod.curves_from_objects([ob])
    c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    expected = np.array([[2 * (c * x - s * y) + 12.0, 2 * (s * x + c * y) - 7.0] for _, (x, y), _ in VALLEY])
    starts = np.array([seg.start for seg in curve.segments] + [curve.segments[-1].end])
    np.testing.assert_allclose(starts, expected, atol=1e-4)


def test_several_splines_unit_scale_and_poly(mod, clean_scene):
    clean_scene.unit_settings.scale_length = 1.0  # 1 BU = 1 m
    ob = bezier_object("Pair", VALLEY, role="MOUNTAIN", scale=0.001)
    add_bezier_spline(ob.data, MOUNTAIN, scale=0.001)
    sp = ob.data.splines.new("POLY")
    sp.points.add(2)
    for p, (x, y) in zip(sp.points, [(0.0, 0.0), (0.05, 0.0), (0.05, 0.05)], strict=True):
        p.co = (x, y, 0.0, 1.0)
    curves = mod.curves_from_objects([ob])
    assert [c.source for c in curves] == [f"curve 'Pair' spline {k}" for k in range(3)]
    assert all(c.assignment == "M" and c.fold_angle == -180.0 for c in curves)
    np.testing.assert_allclose(curves[0].segments[0].start, VALLEY[0][1], rtol=1e-6)
    np.testing.assert_allclose(curves[1].segments[-1].end, MOUNTAIN[-1][1], rtol=1e-6)
    assert [s.kind for s in curves[2].segments] == ["line", "line"]
    np.testing.assert_allclose(curves[2].segments[1].end, (50.0, 50.0), rtol=1e-6)
    # An explicit unit scale wins over the scene's: 1 BU = 1 mm here.
    explicit = mod.curves_from_objects([ob], unit_scale=1.0)
    np.testing.assert_allclose(explicit[0].segments[0].start, np.array(VALLEY[0][1]) * 0.001, rtol=1e-6)
    # Bézier segments whose handles sit on the chord are straight lines.
    straight = bezier_object("Straight", [((0, 0), (0, 0), (10, 0)), ((20, 0), (30, 0), (30, 0))], role="VALLEY")
    (line,) = mod.curves_from_objects([straight], unit_scale=1.0)
    assert [s.kind for s in line.segments] == ["line"]


def test_errors_and_warnings_name_the_curve(mod, clean_scene):
    mm_per_bu_one(clean_scene)
    plain = bezier_object("NoRole", VALLEY, role="NONE")
    with pytest.raises(mod.PatternError, match="no crease curves selected"):
        mod.curves_from_objects([plain])
    valley = bezier_object("Valley", VALLEY, role="VALLEY")
    notes: list[str] = []
    curves = mod.curves_from_objects([plain, valley], warnings=notes)
    assert len(curves) == 1 and any("'NoRole'" in n for n in notes)

    tilted = bezier_object("Tilted", VALLEY, role="VALLEY")
    tilted.rotation_euler = (math.radians(10.0), 0.0, 0.0)
    bpy.context.view_layer.update()
    with pytest.raises(mod.PatternError, match="curve 'Tilted' spline 0 is not flat"):
        mod.curves_from_objects([valley, tilted])
    noisy = bezier_object("Noisy", MOUNTAIN, role="MOUNTAIN")  # 20 µm of z noise on a ~100 mm pattern: read
    noisy.data.splines[0].bezier_points[0].co.z += 0.02
    noisy.location.z = -0.015
    bpy.context.view_layer.update()
    assert len(mod.curves_from_objects([valley, noisy])) == 2
    raised = bezier_object("Raised", MOUNTAIN, role="MOUNTAIN")
    raised.location.z = 5.0
    bpy.context.view_layer.update()
    with pytest.raises(mod.PatternError, match="curve 'Raised' spline 0 lies at z = 5"):
        mod.curves_from_objects([valley, raised])
    nurbs = bpy.data.curves.new("N", "CURVE")
    nurbs.splines.new("NURBS").points.add(3)
    ob = bpy.data.objects.new("Nurbs", nurbs)
    ob.curved_fold.role = "CUT"
    with pytest.raises(mod.PatternError, match="curve 'Nurbs' spline 0 is a NURBS spline"):
        mod.curves_from_objects([ob])


def test_objects_from_curves_round_trip(mod, clean_scene):
    mm_per_bu_one(clean_scene)
    arc = CurveSegment("arc", np.array([[60.0, 50.0], [40.0, 50.0]]), arc=(50.0, 50.0, 10.0, 10.0, 0.0, 0.0, math.pi))
    curves = [
        CreaseCurve([CurveSegment("line", np.array([[0.0, 0.0], [200.0, 0.0]]))], "B", None, source="b"),
        CreaseCurve([CurveSegment("cubic", np.array([[0, 0], [10, 30], [20, -30], [30, 0.5]]))], "V", 120.0),
        CreaseCurve([arc], "M", -45.0),
        CreaseCurve(
            [
                CurveSegment("line", np.array([[0.0, 0.0], [10.0, 0.0]])),
                CurveSegment("line", np.array([[10.0, 0.0], [10.0, 10.0]])),
                CurveSegment("line", np.array([[10.0, 10.0], [0.0, 0.0]])),
            ],
            "C",
            None,
            closed=True,
        ),
    ]
    coll = bpy.data.collections.new("Imported")
    clean_scene.collection.children.link(coll)
    objects = mod.objects_from_curves(curves, coll)
    assert [ob.curved_fold.role for ob in objects] == ["BORDER", "VALLEY", "MOUNTAIN", "CUT"]
    assert [ob.name for ob in objects] == ["Border", "Valley 120°", "Mountain 45°", "Cut"]
    assert [round(math.degrees(ob.curved_fold.fold_angle), 4) for ob in objects[1:3]] == [120.0, 45.0]
    assert all(ob.name in coll.objects for ob in objects)
    assert [s.type for ob in objects for s in ob.data.splines] == ["POLY", "BEZIER", "BEZIER", "POLY"]
    back = mod.curves_from_objects(objects)
    assert [c.assignment for c in back] == ["B", "V", "M", "C"]
    assert [c.fold_angle for c in back] == [None, 120.0, -45.0, None]
    # Unedited: the exact strokes come back (double precision, the arc as an arc).
    for got, want in zip(back, curves, strict=True):
        assert [s.kind for s in got.segments] == [s.kind for s in want.segments]
        for sa, sb in zip(got.segments, want.segments, strict=True):
            np.testing.assert_array_equal(sa.points, sb.points)
            assert sa.arc == sb.arc
    # Edited: what Blender draws. The arc spline with a handle moved back and forth by a float32 step more than
    # the match allows is read as its two ≤ 90° cubic pieces.
    bp = objects[2].data.splines[0].bezier_points[1]
    bp.handle_left.x += 1e-3
    bp.handle_left.x -= 1e-3 - 1e-4
    back = mod.curves_from_objects(objects)
    assert len(back[2].segments) == 2 and {s.kind for s in back[2].segments} == {"cubic"}
    t = np.linspace(0, 1, 41)
    pts = np.concatenate([s.evaluate(t) for s in back[2].segments])
    assert np.max(np.abs(np.hypot(pts[:, 0] - 50.0, pts[:, 1] - 50.0) - 10.0)) < 10.0 * 3e-4 + 1e-3
    np.testing.assert_allclose(back[2].segments[0].start, (60.0, 50.0), atol=1e-5)
    np.testing.assert_allclose(back[2].segments[-1].end, (40.0, 50.0), atol=1e-5)
    assert back[3].closed and [s.kind for s in back[3].segments] == ["line"] * 3


def test_curves_are_read_in_units_for_a_job(mod, clean_scene):
    """``curves_steps`` (a Blender job reads the curves one unit per slice): with a zero budget it yields before
    every spline, and returns exactly what ``curves_from_objects`` returns."""
    mm_per_bu_one(clean_scene)
    objects = [
        poly_object("Border", BORDER, role="BORDER"),
        bezier_object("Valley", VALLEY, role="VALLEY"),
        bezier_object("Mountain", MOUNTAIN, role="MOUNTAIN", angle=90.0),
    ]
    steps = mod.curves_steps(objects, unit_ms=0.0)
    assert list(itertools.islice(steps, 3)) == [None, None, None]  # three splines, one unit each
    with pytest.raises(StopIteration) as done:
        next(steps)
    whole = mod.curves_from_objects(objects)
    assert [c.source for c in done.value.value] == [c.source for c in whole]
    for a, b in zip(done.value.value, whole, strict=True):
        assert [s.kind for s in a.segments] == [s.kind for s in b.segments]
        for sa, sb in zip(a.segments, b.segments, strict=True):
            np.testing.assert_array_equal(sa.points, sb.points)


def test_read_blend_file_leaves_the_open_file_alone(mod, clean_scene, tmp_path):
    mm_per_bu_one(clean_scene)
    bezier_object("Valley", VALLEY, role="VALLEY")
    bezier_object("Plain", MOUNTAIN, role="NONE")
    poly_object("Border", BORDER, role="BORDER")
    path = tmp_path / "pattern.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    expected = mod.curves_from_objects(list(clean_scene.objects))

    bpy.ops.wm.read_homefile(use_empty=True)
    before = {name: len(getattr(bpy.data, name)) for name in ("objects", "curves", "libraries", "scenes")}
    curves, warnings = mod.read_blend_file(path)
    assert warnings == []
    after = {name: len(getattr(bpy.data, name)) for name in ("objects", "curves", "libraries", "scenes")}
    assert after == before
    assert sorted(c.source for c in curves) == sorted(c.source for c in expected)
    by_source = {c.source: c for c in curves}
    for c in expected:
        got = by_source[c.source]
        assert (got.assignment, got.fold_angle, got.closed) == (c.assignment, c.fold_angle, c.closed)
        for sa, sb in zip(got.segments, c.segments, strict=True):
            np.testing.assert_allclose(sa.points, sb.points, atol=1e-9)
    with pytest.raises(mod.PatternError, match="no such file"):
        mod.read_blend_file(tmp_path / "missing.blend")
    (tmp_path / "text.blend").write_text("not a blend file")
    with pytest.raises(mod.PatternError, match="text.blend: cannot read as a .blend file"):
        mod.read_blend_file(tmp_path / "text.blend")
    # a .blend cut short: Blender's message ends in a newline, the refusal is one line (a CLI review session)
    whole = tmp_path / "whole.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(whole), copy=True)
    (tmp_path / "cut.blend").write_bytes(whole.read_bytes()[:2000])
    with pytest.raises(mod.PatternError, match="cut.blend: cannot read as a .blend file") as refused:
        mod.read_blend_file(tmp_path / "cut.blend")
    assert "\n" not in str(refused.value), str(refused.value)
    assert len(bpy.data.libraries) == 0


def test_read_blend_file_places_curves_as_blender_shows_them(mod, clean_scene, tmp_path):
    """A .blend file read from disk (the command line's input) gives the curves where the viewport draws them: moved,
    rotated, mirrored, delta-transformed and parented objects included (linked objects are in no scene, so Blender
    leaves their matrix_world at the identity; the command line read every crease at its object origin)."""
    mm_per_bu_one(clean_scene)
    parent = bpy.data.objects.new("Rig", None)
    clean_scene.collection.objects.link(parent)
    parent.location = (7.0, -3.0, 0.0)
    parent.rotation_euler.z = 0.4
    parent.scale = (1.5, 1.5, 1.5)
    border = poly_object("Border", BORDER, role="BORDER")
    border.parent = parent
    valley = bezier_object("Valley", VALLEY, role="VALLEY", angle=90.0)
    valley.parent = parent
    valley.location.x = 12.0
    valley.delta_rotation_euler.z = 0.1
    mountain = bezier_object("Mountain", MOUNTAIN, role="MOUNTAIN", angle=60.0)
    mountain.parent = valley
    mountain.scale.x = -1.0
    mountain.location.x = 100.0
    bpy.context.view_layer.update()
    expected = mod.curves_from_objects([border, valley, mountain])
    path = tmp_path / "moved.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)

    bpy.ops.wm.read_homefile(use_empty=True)
    curves, warnings = mod.read_blend_file(path)
    assert warnings == []
    by_source = {c.source: c for c in curves}
    assert sorted(by_source) == sorted(c.source for c in expected)
    for c in expected:
        for sa, sb in zip(by_source[c.source].segments, c.segments, strict=True):
            np.testing.assert_allclose(sa.points, sb.points, atol=1e-4)


def test_read_blend_file_reads_the_scene_or_a_chosen_collection(mod, clean_scene, tmp_path):
    """The command line folds what the file's scene shows: an old version kept in a collection excluded from the
    view layer is left out (named in a warning), two patterns side by side are warned about, and ``collection``
    picks one; an unknown collection is one clear error listing those there are."""
    mm_per_bu_one(clean_scene)
    made = {}
    for name, dx in (("A", 0.0), ("B", 300.0), ("Old", 600.0)):
        coll = bpy.data.collections.new(name)
        clean_scene.collection.children.link(coll)
        for ob in (
            poly_object(f"Border {name}", [(x + dx, y) for x, y in BORDER], role="BORDER"),
            bezier_object(f"Valley {name}", [tuple((x + dx, y) for x, y in k) for k in VALLEY], role="VALLEY"),
        ):
            for c in ob.users_collection:
                c.objects.unlink(ob)
            coll.objects.link(ob)
        made[name] = coll
    bpy.context.view_layer.layer_collection.children["Old"].exclude = True
    path = tmp_path / "versions.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)

    bpy.ops.wm.read_homefile(use_empty=True)
    curves, warnings = mod.read_blend_file(path)
    assert sorted(c.source.split("'")[1] for c in curves) == ["Border A", "Border B", "Valley A", "Valley B"]
    assert any("'Border Old'" in w and "excluded from the view layer" in w for w in warnings)
    assert any("2 collections ('A', 'B')" in w and "--collection" in w for w in warnings)
    curves, warnings = mod.read_blend_file(path, collection="Old")
    assert sorted(c.source.split("'")[1] for c in curves) == ["Border Old", "Valley Old"]
    assert warnings == []
    with pytest.raises(
        mod.PatternError, match=r"versions.blend: no collection named 'C' \(the file has 'A', 'B', 'Old'\)"
    ):
        mod.read_blend_file(path, collection="C")
    assert len(bpy.data.libraries) == 0


def test_what_the_viewport_draws_but_does_not_fold_is_said(extension, mod, clean_scene):
    """Modifiers and shape keys change what the viewport draws, not the splines that fold: a Mirror modifier's
    second valley was left out without a word. The warnings reach the fold's pattern (the Fold operator's
    report), as a one-point spline's does; before, the operators dropped every warning met reading the curves."""
    mm_per_bu_one(clean_scene)
    border = poly_object("Border", BORDER, role="BORDER")
    valley = bezier_object("Valley", VALLEY, role="VALLEY", angle=90.0)
    valley.modifiers.new("Mirror", "MIRROR")
    mountain = bezier_object("Mountain", MOUNTAIN, role="MOUNTAIN", angle=90.0)
    mountain.shape_key_add(name="Basis")
    mountain.shape_key_add(name="Bent", from_mix=False).value = 1.0
    point = mountain.data.splines.new("POLY")  # a stray one-point spline
    point.points[0].co = (5.0, 5.0, 0.0, 1.0)
    notes: list[str] = []
    mod.curves_from_objects([border, valley, mountain], warnings=notes)
    assert any("curve 'Valley': its modifier(s) 'Mirror' are not folded" in w for w in notes), notes
    assert any("curve 'Mountain': its shape keys are not folded" in w for w in notes), notes
    assert any("curve 'Mountain' spline 1: fewer than two points, skipped" in w for w in notes), notes
    folding = importlib.import_module(extension.__name__ + ".scene.folding")
    pattern = folding.pattern_from_objects([border, valley, mountain])
    assert [w for w in pattern.warnings if w in notes] == notes
    valley.modifiers[0].show_viewport = False
    mountain.data.shape_keys.key_blocks["Bent"].value = 0.0
    notes.clear()
    mod.curves_from_objects([border, valley, mountain], warnings=notes)
    assert not any("not folded" in w for w in notes), notes


def test_objects_from_curves_failure_creates_nothing(mod, clean_scene):
    good = CreaseCurve([CurveSegment("line", np.array([[0.0, 0.0], [10.0, 0.0]]))], "V", 90.0, source="good")
    bad = CreaseCurve(
        [CurveSegment("line", np.array([[0.0, 0.0], [0.0, 10.0]]))], "X", None, source="SVG <path> (line 7)"
    )
    with pytest.raises(mod.PatternError, match=r"SVG <path> \(line 7\): unknown assignment 'X'"):
        mod.objects_from_curves([good, bad], clean_scene.collection)
    assert len(bpy.data.objects) == 0 and len(bpy.data.curves) == 0


def test_set_crease_role_operator_colours_and_selects(extension, clean_scene):
    properties = importlib.import_module(extension.__name__ + ".scene.properties")
    a = bezier_object("A", VALLEY, role="NONE")
    b = bezier_object("B", MOUNTAIN, role="NONE")
    mesh_ob = bpy.data.objects.new("M", bpy.data.meshes.new("M"))
    clean_scene.collection.objects.link(mesh_ob)
    for ob in (a, b, mesh_ob):
        ob.select_set(True)
    with bpy.context.temp_override(selected_objects=[a, b, mesh_ob], active_object=a):
        assert bpy.ops.curved_fold.set_crease_role(role="MOUNTAIN", fold_angle=math.radians(75.0)) == {"FINISHED"}
    for ob in (a, b):
        assert ob.curved_fold.role == "MOUNTAIN" and ob.curved_fold.fold_angle == pytest.approx(math.radians(75.0))
        assert tuple(ob.color) == pytest.approx(properties.ROLE_COLOURS["MOUNTAIN"])
        slot = ob.material_slots[0]  # the role's material is the object's: the curve data keeps its own
        assert slot.link == "OBJECT" and slot.material.name == "Curved Fold Mountain"
        assert tuple(slot.material.diffuse_color) == pytest.approx((1.0, 0.0, 0.0, 1.0))
        assert list(ob.data.materials) == [None]
        assert ob.data.bevel_depth > 0.0
    assert "curved_fold" not in mesh_ob.keys() or mesh_ob.curved_fold.role == "NONE"
    with bpy.context.temp_override(selected_objects=[mesh_ob]):
        assert not bpy.ops.curved_fold.set_crease_role.poll()
    b.curved_fold.role = "VALLEY"
    assert b.material_slots[0].material.name == "Curved Fold Valley"
    assert bpy.ops.curved_fold.select_by_role(role="VALLEY") == {"FINISHED"}
    assert [ob.name for ob in clean_scene.objects if ob.select_get()] == ["B"]
    # Clearing the role takes the role's colour, material and automatic bevel away again.
    b.curved_fold.role = "NONE"
    assert len(b.data.materials) == 0 and len(b.material_slots) == 0
    assert b.data.bevel_depth == 0.0 and tuple(b.color) == (1.0, 1.0, 1.0, 1.0)
    assert "cf_role_style" not in b and "cf_role_style" not in b.data


def styled_curve(name: str, *, fill: str = "BOTH", colour=(1.0, 0.8, 0.0, 1.0)):
    """A closed 2D Poly curve styled by its user: material "Gold" in the data's slot 0, an object colour, a fill."""
    cu = bpy.data.curves.new(name, "CURVE")
    cu.dimensions = "2D"
    cu.fill_mode = fill
    cu.bevel_resolution = 6
    sp = cu.splines.new("POLY")
    sp.points.add(2)
    for q, p in zip(sp.points, [(0.0, 0.0), (0.05, 0.08), (0.1, 0.0)], strict=True):
        q.co = (*p, 0.0, 1.0)
    sp.use_cyclic_u = True
    gold = bpy.data.materials.get("Gold") or bpy.data.materials.new("Gold")
    cu.materials.append(gold)
    ob = bpy.data.objects.new(name, cu)
    bpy.context.scene.collection.objects.link(ob)
    ob.color = colour
    return ob


def styling(ob) -> dict:
    """What the user sees of a curve's own styling (data materials, object slots, colour, fill, bevel)."""
    cu = ob.data
    return {
        "data_materials": [m.name if m else None for m in cu.materials],
        "slots": [(s.link, s.material.name if s.material else None) for s in ob.material_slots],
        "colour": tuple(round(c, 4) for c in ob.color),
        "fill": cu.fill_mode,
        "bevel": (round(cu.bevel_depth, 7), cu.bevel_resolution),
    }


def test_a_role_keeps_the_users_styling_and_none_puts_it_back(extension, clean_scene):
    """Tester's repro: Set Crease Role replaced the curve's "Gold" material (slot 0), its object colour and 2D fill
    BOTH, and setting the role back to None left no material, a white colour and fill NONE; a linked duplicate's
    material changed too. Now the role shows through the object's own slots and colour, and None restores all."""
    ob = styled_curve("Logo")
    dup = bpy.data.objects.new("Logo copy", ob.data)  # a linked duplicate: same curve data
    clean_scene.collection.objects.link(dup)
    own, dup_own = styling(ob), styling(dup)
    with bpy.context.temp_override(selected_objects=[ob], active_object=ob):
        assert bpy.ops.curved_fold.set_crease_role(role="VALLEY") == {"FINISHED"}
    shown = styling(ob)
    assert shown["data_materials"] == ["Gold"] and shown["slots"] == [("OBJECT", "Curved Fold Valley")]
    assert shown["colour"] == (0.0, 0.0, 1.0, 1.0) and shown["fill"] == "NONE" and shown["bevel"][0] > 0.0
    assert styling(dup)["slots"] == [("DATA", "Gold")] and styling(dup)["colour"] == dup_own["colour"]
    ob.curved_fold.role = "MOUNTAIN"  # role to role: still the user's styling underneath
    assert styling(ob)["slots"] == [("OBJECT", "Curved Fold Mountain")]
    with bpy.context.temp_override(selected_objects=[ob], active_object=ob):
        assert bpy.ops.curved_fold.set_crease_role(role="NONE") == {"FINISHED"}
    assert styling(ob) == own and styling(dup) == dup_own
    assert "cf_role_style" not in ob and "cf_role_style" not in ob.data


def test_role_display_with_object_materials_duplicates_and_user_changes(extension, clean_scene):
    """An object-linked material of the user's comes back; the shared curve's fill and bevel come back only when
    no linked duplicate shows a role any more; a colour or fill the user changes while the role is set stays."""
    ob = styled_curve("Logo")
    silver = bpy.data.materials.new("Silver")
    ob.material_slots[0].link = "OBJECT"
    ob.material_slots[0].material = silver
    dup = bpy.data.objects.new("Logo copy", ob.data)
    clean_scene.collection.objects.link(dup)
    own, dup_own = styling(ob), styling(dup)
    ob.curved_fold.role = "BORDER"
    dup.curved_fold.role = "CUT"
    assert styling(ob)["slots"] == [("OBJECT", "Curved Fold Border")]
    assert styling(dup)["slots"] == [("OBJECT", "Curved Fold Cut")]
    ob.curved_fold.role = "NONE"
    assert styling(ob)["slots"] == own["slots"] and styling(ob)["colour"] == own["colour"]
    assert styling(ob)["fill"] == "NONE" and styling(ob)["bevel"][0] > 0.0  # the duplicate still shows its role
    dup.color = (0.2, 0.3, 0.4, 1.0)  # the user's own change while the role is set: kept
    dup.curved_fold.role = "NONE"
    assert styling(dup) == dict(dup_own, colour=(0.2, 0.3, 0.4, 1.0))
    assert styling(ob) == own
    ob.curved_fold.role = "FACET"
    ob.data.fill_mode = "FRONT"
    ob.curved_fold.role = "NONE"
    assert styling(ob)["fill"] == "FRONT"


def test_role_display_follows_undo_and_reload(extension, clean_scene, tmp_path):
    """What a role replaced is kept in ID properties: undo takes the role display back, and a file saved with a
    role set restores the user's styling when the role is cleared after reopening."""
    ob = styled_curve("Logo")
    own = styling(ob)
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    bpy.ops.ed.undo_push(message="styled")
    assert bpy.ops.curved_fold.set_crease_role("EXEC_DEFAULT", True, role="VALLEY") == {"FINISHED"}
    assert styling(bpy.data.objects["Logo"]) != own
    assert bpy.ops.ed.undo() == {"FINISHED"}
    ob = bpy.data.objects["Logo"]
    assert styling(ob) == own and ob.curved_fold.role == "NONE"
    assert bpy.ops.ed.redo() == {"FINISHED"}
    assert bpy.data.objects["Logo"].curved_fold.role == "VALLEY"
    path = tmp_path / "styled.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.open_mainfile(filepath=str(path))
    ob = bpy.data.objects["Logo"]
    ob.curved_fold.role = "NONE"
    assert styling(ob) == own


def test_a_curve_styled_by_an_older_version_is_cleared_as_before(extension, clean_scene):
    """Files from before: the role material sits in the data's slot 0 and nothing was remembered. Clearing the
    role removes it, the role colour and the automatic bevel (what that version did); a new role then starts from
    there. A curve that never had a role is left alone when set to None."""
    ob = styled_curve("Old", colour=(0.0, 0.0, 1.0, 1.0))
    ob.data.materials[0] = bpy.data.materials.new("Curved Fold Valley")
    ob.data.bevel_depth = 0.0004
    ob.data["cf_auto_bevel"] = True
    plain = styled_curve("Plain", colour=(1.0, 0.0, 0.0, 1.0))  # pure red, as a mountain, but never a role
    before = styling(plain)
    plain.curved_fold.role = "NONE"
    assert styling(plain) == before
    ob.curved_fold.role = "MOUNTAIN"
    assert styling(ob)["data_materials"] == [None] and styling(ob)["slots"] == [("OBJECT", "Curved Fold Mountain")]
    ob.curved_fold.role = "NONE"
    assert styling(ob)["data_materials"] == [] and styling(ob)["colour"] == (1.0, 1.0, 1.0, 1.0)
    assert styling(ob)["bevel"][0] == 0.0


def test_command_line_reads_a_blend_file(mod, clean_scene, tmp_path):
    """``python -m curved_fold discretize x.blend`` in a fresh process (add-on not enabled) reads the crease curves."""
    import json
    import os
    import subprocess
    import sys

    mm_per_bu_one(clean_scene)
    bezier_object("Valley", VALLEY, role="VALLEY")
    poly_object("Border", BORDER, role="BORDER")
    bezier_object("Ignored", MOUNTAIN, role="NONE")
    blend = tmp_path / "drawn.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = tmp_path / "drawn.fold"
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    cmd = [sys.executable, "-m", "curved_fold", "discretize", str(blend), "--out", str(out), "--interval", "10"]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    fold = json.loads(out.read_text())
    assignments = fold["edges_assignment"]
    assert set(assignments) == {"B", "V"}
    assert assignments.count("V") > 5
    xs = [v[0] for v in fold["vertices_coords"]]
    assert min(xs) == pytest.approx(0.0, abs=1e-6) and max(xs) == pytest.approx(200.0, abs=1e-6)


def test_crease_role_panel_polls_for_the_active_curve(extension, view3d):
    panel = bpy.types.VIEW3D_PT_curved_fold_crease_role
    assert (panel.bl_space_type, panel.bl_region_type, panel.bl_category) == ("VIEW_3D", "UI", "Curved Fold")
    ob = bezier_object("Active", VALLEY, role="VALLEY")
    with bpy.context.temp_override(**view3d, active_object=ob, object=ob):
        assert panel.poll(bpy.context)
    mesh_ob = bpy.data.objects.new("Mesh", bpy.data.meshes.new("Mesh"))
    with bpy.context.temp_override(**view3d, active_object=mesh_ob, object=mesh_ob):
        assert not panel.poll(bpy.context)
