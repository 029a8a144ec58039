"""SVG reading in Origami Simulator's convention: fixtures, every path command, transforms, units, CSS, errors."""

from __future__ import annotations

import math
import re
import time
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.io.svg import PX_MM, parse_svg_text, read_svg, stroke_assignment
from curved_fold.core.pattern.model import CurveSegment, PatternError

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"
FIXTURE_FILES = sorted(FIXTURES.glob("*.svg")) if FIXTURES.is_dir() else []

# Independent colour table (origami-simulator-model.md §5.1), used to count the files' elements without core.io.svg.
COLOUR_TABLE = {
    **dict.fromkeys(["#000000", "#000", "black", "rgb(0,0,0)"], "B"),
    **dict.fromkeys(["#ff0000", "#f00", "red", "rgb(255,0,0)"], "M"),
    **dict.fromkeys(["#0000ff", "#00f", "blue", "rgb(0,0,255)"], "V"),
    **dict.fromkeys(["#00ff00", "#0f0", "green", "rgb(0,255,0)"], "C"),
    **dict.fromkeys(["#ffff00", "#ff0", "yellow", "rgb(255,255,0)"], "F"),
    **dict.fromkeys(["#ff00ff", "#f0f", "magenta", "rgb(255,0,255)"], "U"),
}
SUBPATH = re.compile(r"[Mm][^MmZz]*?[LlHhVvCcSsQqTtAa]")


def count_by_colour(path: Path) -> Counter:
    """Elements (sub-paths for <path>) per assignment, by a plain ElementTree walk and regexes."""
    counts: Counter = Counter()
    for elem in ET.parse(path).iter():
        tag = elem.tag.rsplit("}", 1)[-1]
        if tag not in {"path", "line", "polyline", "polygon", "rect", "circle", "ellipse"}:
            continue
        stroke = elem.get("stroke")
        style = elem.get("style", "")
        m = re.search(r"stroke\s*:\s*([^;]+)", style)
        if m:
            stroke = m.group(1)
        a = COLOUR_TABLE.get((stroke or "").strip().lower().replace(" ", ""))
        if a is None:
            continue
        counts[a] += len(SUBPATH.findall(elem.get("d", ""))) if tag == "path" else 1
    return counts


def svg(body: str, head: str = 'viewBox="0 0 100 100" width="100mm" height="100mm"') -> str:
    return f'<svg xmlns="http://www.w3.org/2000/svg" {head}>\n{body}\n</svg>'


def curves_of(body: str, **kw):
    return parse_svg_text(svg(body, **kw), "test.svg").curves


def user(points) -> np.ndarray:
    """User units (viewBox 0 0 100 100 on 100 mm, so 1 unit = 1 mm) → mm, y up."""
    p = np.asarray(points, dtype=float)
    return p * np.array([1.0, -1.0])


# ------------------------------------------------------------------------------------------------ fixtures


@pytest.mark.parametrize("path", FIXTURE_FILES, ids=lambda p: p.name)
def test_fixture_counts_match_the_file(path: Path) -> None:
    drawing = read_svg(path)
    ours = Counter(c.assignment for c in drawing.curves)
    assert ours == count_by_colour(path)
    assert drawing.width_mm > 0 and drawing.height_mm > 0
    for c in drawing.curves:
        assert re.match(r"SVG <\w+( id='[^']*')?> \(line \d+\)", c.source), c.source
        for s in c.segments:
            assert np.all(np.isfinite(s.points))


def test_fixture_counts_match_the_reference_table() -> None:
    expected = {
        "wavy_pleats.svg": {"B": 1, "M": 3, "V": 2},
        "CircularPleat-antiFacet.svg": {"B": 200, "M": 700, "V": 700, "F": 1600},
        "shell14.svg": {"B": 70, "M": 560, "V": 560, "F": 1064},
        "Rotating_Star.svg": {"B": 1, "M": 12, "V": 24},
        "Carved_Cylinder.svg": {"B": 1, "M": 40, "V": 40},
        "Treble_Clef.svg": {"B": 1, "M": 1},
    }
    for name, counts in expected.items():
        got = Counter(c.assignment for c in read_svg(FIXTURES / name).curves)
        assert dict(got) == counts, name
    huffman = Counter(c.assignment for c in read_svg(FIXTURES / "huffmanTower.svg").curves)
    assert huffman["U"] == 13 and huffman["B"] == 12


def test_fixture_fold_angles_from_opacity() -> None:
    angles = Counter((c.assignment, c.fold_angle) for c in read_svg(FIXTURES / "shell14.svg").curves)
    assert angles[("M", -90.0)] == 560 and angles[("V", 90.0)] == 560 and angles[("F", 0.0)] == 1064
    assert angles[("B", None)] == 70
    huff = {
        (c.assignment, round(c.fold_angle, 6)) for c in read_svg(FIXTURES / "huffmanTower.svg").curves if c.fold_angle
    }
    assert ("V", 54.0) in huff and ("M", -54.0) in huff and ("M", round(-0.3333 * 180, 6)) in huff
    wavy = read_svg(FIXTURES / "wavy_pleats.svg")
    assert {c.fold_angle for c in wavy.curves if c.assignment == "M"} == {-180.0}
    # 426.2 px wide without physical units → mm at 25.4/96
    assert wavy.width_mm == pytest.approx(426.2 * PX_MM)
    assert all(c.is_curved for c in wavy.curves if c.assignment != "B")


def test_treble_clef_border_is_one_closed_curved_path() -> None:
    border = [c for c in read_svg(FIXTURES / "Treble_Clef.svg").curves if c.assignment == "B"]
    assert len(border) == 1 and border[0].closed and border[0].is_curved
    segs = border[0].segments
    for s0, s1 in zip(segs, segs[1:] + segs[:1], strict=True):
        np.testing.assert_allclose(s0.points[-1], s1.points[0], atol=1e-12)


# ------------------------------------------------------------------------------------------------ path data


def test_move_line_horizontal_vertical_absolute_relative_and_implicit_repeats() -> None:
    (c,) = curves_of('<path stroke="red" d="M10 10 L20 10 30 20 h5 v-5 H50 V40 l-5,5 5 5"/>')
    pts = [c.segments[0].points[0]] + [s.points[1] for s in c.segments]
    np.testing.assert_allclose(
        pts, user([[10, 10], [20, 10], [30, 20], [35, 20], [35, 15], [50, 15], [50, 40], [45, 45], [50, 50]])
    )
    assert all(s.kind == "line" for s in c.segments) and not c.closed
    assert c.fold_angle == -180.0 and c.assignment == "M"


def test_relative_move_implicit_lineto_and_compact_numbers() -> None:
    (c,) = curves_of('<path stroke="blue" d="m10-5.5.5.5l1e1,0"/>')
    pts = [c.segments[0].points[0]] + [s.points[1] for s in c.segments]
    np.testing.assert_allclose(pts, user([[10, -5.5], [10.5, -5], [20.5, -5]]))


def test_cubic_and_smooth_cubic_reflect_the_control_point() -> None:
    (c,) = curves_of('<path stroke="red" d="M0 0 C 10 0 20 10 20 20 S 30 40 40 40 s 10 -10 20 0"/>')
    a, b, d = c.segments
    assert a.kind == b.kind == d.kind == "cubic"
    np.testing.assert_allclose(b.points, user([[20, 20], [20, 30], [30, 40], [40, 40]]))  # reflected (20,10)→(20,30)
    np.testing.assert_allclose(d.points, user([[40, 40], [50, 40], [50, 30], [60, 40]]))


def test_smooth_cubic_without_previous_cubic_uses_current_point() -> None:
    (c,) = curves_of('<path stroke="red" d="M0 0 L10 0 S 20 10 30 0"/>')
    np.testing.assert_allclose(c.segments[1].points, user([[10, 0], [10, 0], [20, 10], [30, 0]]))


def test_quadratic_and_smooth_quadratic_are_exact_cubics() -> None:
    (c,) = curves_of('<path stroke="red" d="M0 0 Q 10 20 20 0 T 40 0 t 20 0"/>')
    q = [
        (user([0, 0]), user([10, 20]), user([20, 0])),
        (user([20, 0]), user([30, -20]), user([40, 0])),
        (user([40, 0]), user([50, 20]), user([60, 0])),
    ]
    t = np.linspace(0, 1, 11)[:, None]
    for seg, (p0, p1, p2) in zip(c.segments, q, strict=True):
        exact = (1 - t) ** 2 * p0 + 2 * (1 - t) * t * p1 + t**2 * p2
        np.testing.assert_allclose(seg.evaluate(t[:, 0]), exact, atol=1e-12)


def test_relative_quadratic_and_relative_cubic() -> None:
    (c,) = curves_of('<path stroke="red" d="M10 10 q 5 10 10 0 c 0 5 5 5 5 0"/>')
    np.testing.assert_allclose(c.segments[0].evaluate(1.0), user([20, 10]))
    np.testing.assert_allclose(c.segments[1].points, user([[20, 10], [20, 15], [25, 15], [25, 10]]))


@pytest.mark.parametrize("large,sweep", [(0, 0), (0, 1), (1, 0), (1, 1)])
def test_arc_endpoints_radius_and_flags(large: int, sweep: int) -> None:
    (c,) = curves_of(f'<path stroke="red" d="M10 50 A 25 25 0 {large} {sweep} 50 50"/>')
    (s,) = c.segments
    assert s.kind == "arc"
    cx, cy, rx, ry, phi, theta0, dtheta = s.arc
    np.testing.assert_allclose(s.evaluate(np.array([0.0, 1.0])), user([[10, 50], [50, 50]]), atol=1e-12)
    assert rx == pytest.approx(25) and ry == pytest.approx(25)
    assert abs(dtheta) > math.pi if large else abs(dtheta) < math.pi
    pts = s.evaluate(np.linspace(0, 1, 50))
    np.testing.assert_allclose(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy), 25, atol=1e-9)
    # sweep=1 is clockwise on screen (y down) = clockwise seen y-up? SVG positive angle direction maps to
    # clockwise in y-up coordinates, so dtheta < 0 after the flip.
    assert (dtheta < 0) == bool(sweep)


def test_arc_radii_scale_up_and_zero_radius_is_a_line() -> None:
    cs = curves_of('<path stroke="red" d="M0 50 a 5 5 0 0 1 40 0 M 0 80 a 0 10 0 0 1 40 0"/>')
    assert len(cs) == 2
    arc = cs[0].segments[0]
    assert arc.arc[2] == pytest.approx(20) and arc.arc[3] == pytest.approx(20)  # scaled up to half the chord
    assert cs[1].segments[0].kind == "line"


def test_arc_flags_without_separators() -> None:
    (c,) = curves_of('<path stroke="red" d="M10 10a5 5 0 1010 0"/>')
    np.testing.assert_allclose(c.segments[0].evaluate(1.0), user([20, 10]), atol=1e-12)


def test_close_path_returns_to_subpath_start_and_subpaths_split() -> None:
    cs = curves_of('<path id="p" stroke="black" d="M0 0 h10 v10 z m20 0 h10 v10 Z M50 50 l5 5"/>')
    assert len(cs) == 3
    assert cs[0].closed and cs[1].closed and not cs[2].closed
    np.testing.assert_allclose(cs[0].segments[-1].points, user([[10, 10], [0, 0]]))
    np.testing.assert_allclose(cs[1].segments[0].points[0], user([20, 0]))  # m after z is relative to the start
    np.testing.assert_allclose(cs[1].segments[-1].points[1], user([20, 0]))
    assert cs[2].source.endswith("subpath 3") and "<path id='p'>" in cs[2].source


def test_straight_cubic_is_straight() -> None:
    (c,) = curves_of('<path stroke="red" d="M0 0 C 10 10 20 20 30 30"/>')
    assert c.segments[0].kind == "cubic" and c.segments[0].is_straight and not c.is_curved


@pytest.mark.parametrize(
    "d,token",
    [
        ("M 10 10 L 20 x", "x"),
        ("L 10 10", "L"),
        ("M 10 10 K 5 5", "K"),
        ("M0 0 A 5 5 0 2 1 10 10", "2"),
        ("M 10", "end of data"),
    ],
)
def test_bad_path_data_names_element_line_and_token(d: str, token: str) -> None:
    with pytest.raises(PatternError) as exc:
        parse_svg_text(svg(f'<path id="bad" stroke="red" d="{d}"/>'), "t.svg")
    msg = str(exc.value)
    assert "<path id='bad'>" in msg and "(line 2)" in msg and repr(token) in msg


# ------------------------------------------------------------------------------------------------ elements


def test_line_polyline_polygon_rect() -> None:
    cs = curves_of(
        '<line stroke="red" x1="1" y1="2" x2="3" y2="4"/>\n'
        '<polyline stroke="blue" points="0,0 10,0 10,10"/>\n'
        '<polygon stroke="black" points="0 0 10 0 10 10"/>\n'
        '<rect stroke="yellow" x="5" y="6" width="10" height="20"/>'
    )
    assert [c.assignment for c in cs] == ["M", "V", "B", "F"]
    np.testing.assert_allclose(cs[0].segments[0].points, user([[1, 2], [3, 4]]))
    assert len(cs[1].segments) == 2 and not cs[1].closed
    assert len(cs[2].segments) == 3 and cs[2].closed
    assert len(cs[3].segments) == 4 and cs[3].closed and cs[3].fold_angle == 0.0
    np.testing.assert_allclose(cs[3].segments[1].points, user([[15, 6], [15, 26]]))
    assert cs[1].source == "SVG <polyline> (line 3)"


def test_rounded_rect_circle_ellipse_are_exact_arcs() -> None:
    cs = curves_of(
        '<rect stroke="black" x="10" y="10" width="40" height="20" rx="5"/>\n'
        '<circle stroke="red" cx="50" cy="50" r="10"/>\n'
        '<ellipse stroke="blue" cx="20" cy="70" rx="8" ry="4"/>'
    )
    rect, circle, ellipse = cs
    kinds = Counter(s.kind for s in rect.segments)
    assert kinds == {"line": 4, "arc": 4} and rect.closed
    for a, b in zip(rect.segments, rect.segments[1:] + rect.segments[:1], strict=True):
        np.testing.assert_allclose(a.evaluate(1.0), b.evaluate(0.0), atol=1e-12)
    corner = rect.segments[1]
    assert corner.arc[2] == pytest.approx(5) and corner.arc[3] == pytest.approx(5)  # ry defaults to rx
    pts = np.concatenate([s.evaluate(np.linspace(0, 1, 40)) for s in circle.segments])
    np.testing.assert_allclose(np.hypot(*(pts - user([50, 50])).T), 10, atol=1e-12)
    assert circle.closed and all(s.kind == "arc" for s in circle.segments)
    pe = np.concatenate([s.evaluate(np.linspace(0, 1, 40)) for s in ellipse.segments]) - user([20, 70])
    np.testing.assert_allclose((pe[:, 0] / 8) ** 2 + (pe[:, 1] / 4) ** 2, 1, atol=1e-12)


def test_defs_symbol_clip_and_metadata_contents_are_skipped() -> None:
    cs = curves_of(
        '<defs><path stroke="red" d="M0 0 L1 1"/></defs><symbol><line stroke="red" x2="5"/></symbol>'
        '<clipPath><rect stroke="black" width="5" height="5"/></clipPath><metadata><line stroke="red" x2="1"/>'
        '</metadata><line stroke="blue" x1="0" y1="0" x2="10" y2="0"/>'
    )
    assert [c.assignment for c in cs] == ["V"]


# ------------------------------------------------------------------------------------------------ transforms


def test_transforms_nested_innermost_first() -> None:
    (c,) = curves_of(
        '<g transform="translate(10 20)"><g transform="scale(2)"><line stroke="red" x1="1" y1="1" x2="2" y2="1" '
        'transform="rotate(90)"/></g></g>'
    )
    # rotate(90): (1,1)→(-1,1), (2,1)→(-1,2); scale 2 → (-2,2),(-2,4); translate → (8,22),(8,24)
    np.testing.assert_allclose(c.segments[0].points, user([[8, 22], [8, 24]]), atol=1e-12)


@pytest.mark.parametrize(
    "transform,expected",
    [
        ("matrix(1 2 3 4 5 6)", [1 * 1 + 3 * 2 + 5, 2 * 1 + 4 * 2 + 6]),
        ("translate(5)", [6, 2]),
        ("scale(2, 3)", [2, 6]),
        ("rotate(90 1 0)", [-1, 0]),
        ("skewX(45)", [3, 2]),
        ("skewY(45)", [1, 3]),
        ("translate(1,1) scale(2)", [3, 5]),
    ],
)
def test_each_transform_kind(transform: str, expected: list[float]) -> None:
    (c,) = curves_of(f'<line stroke="red" x1="1" y1="2" x2="50" y2="50" transform="{transform}"/>')
    np.testing.assert_allclose(c.segments[0].points[0], user(expected), atol=1e-12)


@pytest.mark.parametrize(
    "transform", ["matrix(1 0.3 -0.5 -2 10 20)", "scale(-1 1) skewX(20)", "rotate(33) scale(2 .5)"]
)
def test_arc_under_any_affine_transform_is_the_exact_image(transform: str) -> None:
    d = "M10 10 A 20 8 25 0 1 30 25"
    (plain,) = curves_of(f'<path stroke="red" d="{d}"/>')
    (moved,) = curves_of(f'<g transform="{transform}"><path stroke="red" d="{d}"/></g>')
    from curved_fold.core.io.svg import parse_transform

    m = parse_transform(transform)
    t = np.linspace(0, 1, 33)
    user_pts = plain.segments[0].evaluate(t) * np.array([1.0, -1.0])  # back to user units
    expected = (user_pts @ m[:2, :2].T + m[:2, 2]) * np.array([1.0, -1.0])
    np.testing.assert_allclose(moved.segments[0].evaluate(t), expected, atol=1e-9)
    assert moved.segments[0].kind == "arc"


def test_bad_transform_is_reported() -> None:
    with pytest.raises(PatternError, match=r"<line> \(line 2\).*transform"):
        parse_svg_text(svg('<line stroke="red" x2="1" transform="spin(3)"/>'), "t.svg")


# ------------------------------------------------------------------------------------------------ units


@pytest.mark.parametrize(
    "head,scale",
    [
        ('viewBox="0 0 300 300" width="150mm" height="150mm"', 0.5),
        ('viewBox="0 0 100 100" width="10cm" height="10cm"', 1.0),
        ('viewBox="0 0 100 100" width="4in" height="4in"', 25.4 * 4 / 100),
        ('viewBox="0 0 72 72" width="72pt" height="72pt"', 25.4 / 72),
        ('viewBox="0 0 10 10" width="1pc" height="1pc"', 25.4 / 6 / 10),
        ('viewBox="0 0 40 40" width="40Q" height="40Q"', 0.25),
        ('width="300" height="300"', PX_MM),
        ('viewBox="0 0 300 300"', PX_MM),
        ('width="150mm" height="150mm"', PX_MM),  # no viewBox: user units are px whatever the size says
        ('viewBox="0 0 300 300" width="300px" height="300px"', PX_MM),
    ],
)
def test_units_and_viewbox(head: str, scale: float) -> None:
    (c,) = parse_svg_text(svg('<line stroke="red" x1="0" y1="0" x2="10" y2="20"/>', head), "u.svg").curves
    np.testing.assert_allclose(c.segments[0].points[1] - c.segments[0].points[0], [10 * scale, -20 * scale])


def test_lengths_with_absolute_units_on_shapes_are_css_lengths() -> None:
    """``<rect width="150mm">``, ``x1="0mm"``: CSS absolute units on geometry attributes (a user unit is a px, 1/96
    in, as for a root without a viewBox). They were refused ("is not a number in user units"). A tester's file of
    425.19685pt × 15cm without a viewBox: its 150 mm border and the diagonal to (566.929, 566.929) px meet."""
    d = parse_svg_text(
        svg(
            '<rect stroke="#000" width="150mm" height="15cm"/>\n<line stroke="red" x2="566.929" y2="566.929"/>\n'
            '<line stroke="red" x1="1in" y1="72pt" x2="6pc" y2="40Q"/>\n<circle stroke="red" cx="96PX" r="2.54CM"/>',
            head='width="425.19685pt" height="15cm"',
        ),
        "units.svg",
    )
    border, diagonal, mixed, circle = d.curves
    np.testing.assert_allclose(border.segments[1].points, [[150, 0], [150, -150]], atol=1e-9)
    np.testing.assert_allclose(diagonal.segments[0].points[1], [150, -150], atol=1e-4)
    np.testing.assert_allclose(mixed.segments[0].points, [[25.4, -25.4], [25.4, -10]], atol=1e-9)
    np.testing.assert_allclose([circle.segments[0].arc[0], circle.segments[0].arc[2]], [25.4, 25.4], atol=1e-9)
    assert d.warnings == []


def test_lengths_in_mm_under_a_viewbox_of_another_scale_are_drawn_as_browsers_draw_them_and_said() -> None:
    """``x1="50mm"`` is 188.98 user units whatever the viewBox; with ``viewBox="0 0 100 100"`` on 100 mm a user
    unit is 1 mm, so the line lands 189 mm down, off the sheet, as rsvg-convert draws it: one line says why."""
    d = parse_svg_text(
        svg('<line id="u" x1="0mm" y1="50mm" x2="100mm" y2="50mm" stroke="#f00"/>\n<line stroke="red" x2="5px"/>'),
        "unitlen.svg",
    )
    np.testing.assert_allclose(d.curves[0].segments[0].points, [[0, -50 / PX_MM], [100 / PX_MM, -50 / PX_MM]])
    assert d.warnings == [
        "unitlen.svg: lengths with units on shapes are CSS lengths (96 px, that is 96 user units, to the inch), "
        "which this file's viewBox or transforms draw at another size, as browsers do: SVG <line id='u'> (line 2) "
        "(drawn 3.78× the size written); write them without units to mean the file's own units"
    ]


def test_percentages_are_of_the_viewport_and_font_units_are_refused() -> None:
    """Percentages: x and width of the viewport's width, y and height of its height, r of its diagonal / √2
    (SVG 1.1 §7.10), in the user units of the viewBox."""
    (rect, circle) = curves_of(
        '<rect stroke="#000" x="10%" y="50%" width="50%" height="25%"/><circle stroke="red" cx="0" r="10%"/>',
        head='viewBox="0 0 200 100" width="200mm" height="100mm"',
    )
    np.testing.assert_allclose(rect.segments[0].points, [[20, -50], [120, -50]])
    np.testing.assert_allclose(rect.segments[1].points, [[120, -50], [120, -75]])
    assert circle.segments[0].arc[2] == pytest.approx(math.hypot(200, 100) / math.sqrt(2) / 10)
    with pytest.raises(PatternError, match=r"<line> \(line 2\): attribute x2='50%' is a percentage of the viewport"):
        parse_svg_text(svg('<line stroke="red" x2="50%"/>', head=""), "p.svg")
    with pytest.raises(PatternError, match=r"<line id='e'> \(line 2\): attribute x1='2em' is in em, a unit relative"):
        parse_svg_text(svg('<line id="e" stroke="red" x1="2em"/>'), "e.svg")
    with pytest.raises(PatternError, match=r"attribute x1='3furlongs' is not a number \(a length in user units"):
        parse_svg_text(svg('<line stroke="red" x1="3furlongs"/>'), "f.svg")


@pytest.mark.parametrize("size", ["0.15m", "15foo", "10em", "150 mm wide"])
def test_a_sheet_size_that_is_not_an_svg_length_is_refused(size: str) -> None:
    """The root's width in metres (not an SVG unit), in em or with a typo was read as no size: the sheet folded at
    the viewBox's pixel size (39.7 mm instead of 150 mm), silently, where the same unit on a shape is refused (a
    designer session). One line now names it; ``auto``, a percentage or no width still take the viewBox's size."""
    head = f'viewBox="0 0 150 150" width="{size}" height="150mm"'
    with pytest.raises(PatternError) as refused:
        parse_svg_text(svg('<line stroke="red" x2="10"/>', head), "s.svg")
    message = str(refused.value)
    assert message.startswith(f"s.svg: <svg> width={size!r} is not a length the sheet's size can be read from: give a")
    assert message.endswith("(m is not an SVG unit: write it in mm)") == (size == "0.15m")
    for fine in ("auto", "AUTO", "100%", ""):
        d = parse_svg_text(svg('<line stroke="red" x2="10"/>', f'viewBox="0 0 150 150" width="{fine}"'), "s.svg")
        assert d.width_mm == pytest.approx(150 * PX_MM)


def test_viewbox_origin_and_aspect_ratio_meet() -> None:
    head = 'viewBox="10 10 100 50" width="100mm" height="100mm"'  # meet: scale 1, centred vertically (+25 mm)
    d = parse_svg_text(svg('<line stroke="red" x1="10" y1="10" x2="110" y2="60"/>', head), "u.svg")
    np.testing.assert_allclose(d.curves[0].segments[0].points, [[0, -25], [100, -75]])
    assert (d.width_mm, d.height_mm) == (100, 100)


# ------------------------------------------------------------------------------------------------ colours, CSS


@pytest.mark.parametrize(
    "stroke,assignment",
    [
        ("#f00", "M"),
        ("#FF0000", "M"),
        ("red", "M"),
        ("rgb(255, 0, 0)", "M"),
        ("rgb(100%,0%,0%)", "M"),
        (" RED ", "M"),
        ("#00f", "V"),
        ("rgb(0,0,255)", "V"),
        ("blue", "V"),
        ("#000", "B"),
        ("black", "B"),
        ("lime", "C"),
        ("green", "C"),
        ("#0f0", "C"),
        ("yellow", "F"),
        ("#ff0", "F"),
        ("magenta", "U"),
        ("fuchsia", "U"),
        ("#f0f", "U"),
        ("#c80000", None),
        ("#fe0000", None),
        ("rgba(255,0,0,0.5)", "M"),
        ("hsl(0, 100%, 50%)", "M"),
        ("hsl(240deg 100% 50%)", "V"),
        ("hsla(0.5turn,100%,50%,1)", None),  # cyan
        ("rgb(0 0 255)", "V"),
        ("rgb(0 0 255 / 60%)", "V"),
        ("rgb(0% 0% 100%)", "V"),
        ("#ff000099", "M"),
        ("#f009", "M"),
        ("#F00F", "M"),
        ("rgb(0 0 255 0.5)", None),
        ("rgb(0, 0 255)", None),
        ("rgb(255,0,0,0.5,1)", None),
        ("rgb(nan,0,0)", None),  # a ValueError traceback before
        ("rgb(1e999,0,0)", None),  # an OverflowError traceback before
        ("#ff00009", None),
        ("none", None),
        ("gray", None),
        (None, None),
    ],
)
def test_exact_stroke_colour_matching(stroke, assignment) -> None:
    assert stroke_assignment(stroke) == assignment


def test_unknown_colours_are_skipped_with_one_warning() -> None:
    d = parse_svg_text(
        svg(
            '<line stroke="#123456" x2="1"/>\n<line stroke="#123456" x2="2"/>\n<line x2="3"/>\n'
            '<line stroke="red" x2="4"/>\n<line stroke="#123456" x2="5"/>'
        ),
        "w.svg",
    )
    assert len(d.curves) == 1
    assert len(d.warnings) == 1
    w = d.warnings[0]
    assert "#123456 (3 elements: lines 2, 3, 6)" in w and "line 4" not in w  # a line without a stroke: not a crease


def test_opacity_gives_the_fold_angle() -> None:
    cs = curves_of(
        '<line stroke="red" opacity="0.5" x2="1"/><line stroke="blue" stroke-opacity="0.6" x2="1"/>'
        '<line stroke="blue" opacity="0.5" stroke-opacity="0.5" x2="1"/><line stroke="red" opacity="0" x2="1"/>'
        '<line stroke="yellow" opacity="0.3" x2="1"/><line stroke="magenta" x2="1"/><line stroke="black" x2="1"/>'
    )
    angles = [c.fold_angle for c in cs]
    assert angles[:3] == [pytest.approx(-90), pytest.approx(108), pytest.approx(45)]
    assert angles[3:] == [None, 0.0, None, None]


def test_every_css_spelling_of_a_role_colour_is_read_and_its_alpha_is_a_stroke_opacity() -> None:
    """hsl(), rgb() in CSS Color 4's space syntax (with ``/ alpha``), rgba(), percentages, 8- and 4-digit hex: a
    tester's files had them skipped as "unknown stroke colour". The alpha multiplies the fold angle as
    stroke-opacity does (and with it: 0.6 × 0.5 × 180° = 54°)."""
    strokes = [
        'stroke="hsl(0, 100%, 50%)" stroke-opacity="0.6"',
        'stroke="rgb(0 0 255)" stroke-opacity="0.6"',
        'stroke="rgb(0 0 255 / 60%)"',
        'stroke="rgba(255,0,0,0.6)"',
        'stroke="rgb(0%,0%,100%)" stroke-opacity=".6"',
        'stroke="#ff000099"',
        'stroke="#f009"',
        'stroke="rgba(255, 0, 0, .6)" stroke-opacity="0.5"',
        'style="stroke: hsla(240 100% 50% / 0.6)" opacity="0.5"',
    ]
    d = parse_svg_text(svg("\n".join(f'<line {s} x2="1"/>' for s in strokes)), "c.svg")
    assert d.warnings == []
    got = [(c.assignment, round(c.fold_angle, 9)) for c in d.curves]
    assert got == [("M", -108), ("V", 108), ("V", 108), ("M", -108), ("V", 108), ("M", -108), ("M", -108)] + [
        ("M", -54),
        ("V", 54),
    ]


def test_shapes_without_a_stroke_are_skipped_quietly_and_filled_ones_noted() -> None:
    """``stroke="none"`` (LibreOffice's invisible bounding boxes), no stroke or a transparent one draws no line, so
    it cannot be a crease: it is skipped without the "unknown stroke colours" warning that listed it. Only a shape
    filled in a role colour (SVG's default fill is black) is noted, in a line of its own: it may be the sheet drawn
    as a silhouette."""
    d = parse_svg_text(
        svg(
            '<rect class="BoundingBox" stroke="none" fill="none" x="-1" y="-1" width="102" height="102"/>\n'
            '<line id="l" x2="3"/>\n<path stroke="transparent" fill="none" d="M0 0 L1 1"/>\n'
            '<g fill="none"><circle r="4"/></g>\n'
            '<line stroke="red" x2="4"/>\n'
            '<rect id="sheet" width="100" height="100"/>\n<circle stroke="none" fill="#ff0" r="3"/>'
        ),
        "lo.svg",
    )
    assert [c.assignment for c in d.curves] == ["M"]
    assert d.warnings == [
        "lo.svg: 2 filled shape(s) without a stroke skipped (only strokes are read; to make one the sheet's outline, "
        "give it a black stroke): SVG <rect id='sheet'> (line 7), SVG <circle> (line 8)"
    ]


def test_unknown_colour_is_shown_as_written() -> None:
    """The warning quotes the stroke as the file has it: ``rgb(0 0 254)`` was shown as ``rgb(00254)``."""
    d = parse_svg_text(svg('<line stroke="red" x2="1"/>\n<line stroke=" rgb(0 0 254) " x2="1"/>'), "w.svg")
    assert d.warnings == ["w.svg: unknown stroke colours (elements skipped): rgb(0 0 254) (1 element: line 3)"]


def test_a_groups_opacity_is_not_a_fold_angle_and_one_line_says_so() -> None:
    """Inkscape's layer opacity is ``<g opacity="0.6">``: its creases fold by their strokes' own opacity (180° here),
    as before, but no longer silently. One line names each such group that holds creases, with its line and how
    many creases it holds; a use's own opacity is a group's too."""
    d = parse_svg_text(
        svg(
            '<g id="creases" opacity="0.6">\n<line stroke="red" x2="1"/><line stroke="#00f" x2="2"/>\n'
            '<g style="opacity:50%"><line stroke="red" stroke-opacity="0.5" x2="3"/><line stroke="#000" x2="4"/></g>'
            '</g>\n<g opacity="1"><line stroke="red" x2="5"/></g><g opacity="0.3"><line stroke="#000" x2="6"/></g>\n'
            '<use href="#creases" opacity=".5"/>',
            head=XLINK,
        ),
        "g.svg",
    )
    assert [c.fold_angle for c in d.curves] == [-180, 180, -90, None, -180, None, -180, 180, -90, None]
    assert d.warnings == [
        "g.svg: a group's opacity is not read as a fold angle: SVG <g id='creases'> (line 2) has opacity 0.6 around "
        "3 crease(s); SVG <g> (line 4) has opacity 0.5 around 1 crease(s); SVG <use> (line 6) has opacity 0.5 "
        "around 3 crease(s); SVG <g id='creases'> (line 2) via <use> (line 6) has opacity 0.6 around 3 crease(s) "
        "and 1 more; its creases fold by their own strokes' opacity (180° when full): set stroke-opacity (or "
        "opacity) to the fold angle / 180° (0.6 for 108°) on each stroke"
    ]


def test_a_crease_whose_opacity_gives_0_degrees_is_named() -> None:
    """Opacity 0 (of the element, its stroke or its colour's alpha) leaves a mountain or valley without an angle:
    it stays flat unless ``--angle`` gives it one. A tester's file folded nothing ("converged, 0 iterations") and
    said nothing; one line now names the creases."""
    d = parse_svg_text(
        svg(
            '<path id="zero" d="M 75 0 C 55 50 95 100 75 150" stroke="#0000ff" stroke-opacity="0"/>\n'
            '<line stroke="red" opacity="0" x2="1"/><line stroke="#f000" x2="1"/><line stroke="red" x2="1"/>\n'
            '<line stroke="yellow" opacity="0" x2="1"/><line stroke="black" stroke-opacity="0" x2="1"/>'
        ),
        "z.svg",
    )
    assert [c.fold_angle for c in d.curves] == [None, None, None, -180, 0, None]
    assert d.warnings == [
        "z.svg: 3 crease(s) with opacity 0 fold by 0° and stay flat: SVG <path id='zero'> (line 2), SVG <line> "
        "(line 3), SVG <line> (line 3); set stroke-opacity (or opacity) to the fold angle / 180° (0.6 for 108°), "
        "or give creases without an angle one with --angle (command line)"
    ]


def test_css_cascade_inheritance_and_precedence() -> None:
    style = (
        "<style>/* creases */ .m { stroke: #ff0000 } #v1, .valley { stroke: blue; stroke-opacity: .5 }"
        " line { stroke: #000 } g.k > line { stroke: red }</style>"
    )
    d = parse_svg_text(
        svg(
            style
            + '\n<path class="m" d="M0 0 L1 1"/>'  # class → M
            + '\n<path id="v1" d="M0 0 L1 1"/>'  # id → V at 90°
            + '\n<line x2="1"/>'  # type → B
            + '\n<line class="m" x2="1"/>'  # class beats type
            + '\n<line class="m" stroke="blue" x2="1"/>'  # CSS beats presentation attribute
            + '\n<line class="m" style="stroke:blue" x2="1"/>'  # inline beats CSS
            + '\n<g stroke="blue" stroke-opacity="0.5" opacity="0.1"><path d="M0 0 L1 1"/></g>'  # inherited
        ),
        "c.svg",
    )
    got = [(c.assignment, c.fold_angle) for c in d.curves]
    assert got == [("M", -180.0), ("V", 90.0), ("B", None), ("M", -180.0), ("M", -180.0), ("V", 180.0), ("V", 90.0)]
    assert any("g.k > line" in w for w in d.warnings)


# ------------------------------------------------------------------------------------------------ errors


def test_malformed_xml_names_the_line() -> None:
    with pytest.raises(PatternError, match=r"bad\.svg: malformed XML at line 3"):
        parse_svg_text('<svg xmlns="http://www.w3.org/2000/svg">\n<line x2="1"/>\n<path d="M0 0"\n', "bad.svg")


def test_not_an_svg_and_empty_svg() -> None:
    with pytest.raises(PatternError, match=r"not an SVG file \(root element is <html>"):
        parse_svg_text("<html><body/></html>", "x.svg")
    with pytest.raises(PatternError, match="no usable crease element"):
        parse_svg_text(svg('<line stroke="gray" x2="1"/>'), "e.svg")


def test_missing_file_is_a_pattern_error(tmp_path: Path) -> None:
    with pytest.raises(PatternError, match="cannot read SVG file"):
        read_svg(tmp_path / "missing.svg")


def test_bad_attribute_values_are_reported() -> None:
    with pytest.raises(PatternError, match=r"<line> \(line 2\): attribute x1='abc'"):
        parse_svg_text(svg('<line stroke="red" x1="abc" x2="1"/>'), "t.svg")
    with pytest.raises(PatternError, match=r"<line id='o'> \(line 2\): opacity 'half'"):
        parse_svg_text(svg('<line id="o" stroke="red" opacity="half" x2="1"/>'), "t.svg")
    with pytest.raises(PatternError, match="odd number of coordinates"):
        parse_svg_text(svg('<polyline stroke="red" points="0 0 1"/>'), "t.svg")


def test_segments_are_curve_segments() -> None:
    (c,) = curves_of('<path stroke="red" d="M0 0 C 0 10 10 10 10 0"/>')
    assert isinstance(c.segments[0], CurveSegment) and c.is_curved


# ------------------------------------------------------------------------------------------ bounded parsing (issue 16)

HEAD16 = '<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">'
BORDER16 = '<rect x="0" y="0" width="100" height="100" stroke="#000"/>'


def test_css_blocks_scanner_handles_at_rules_nesting_and_unclosed_blocks() -> None:
    from curved_fold.core.io.svg import _css_blocks, _strip_comments

    assert _css_blocks("a{x:1} @media print{b{y:2}} c{z:3") == [
        ("a", "x:1"),
        (" @media print", "b{y:2}"),
        (" c", "z:3"),
    ]
    assert _css_blocks("}}a{b}") == [("a", "b")]
    assert _strip_comments("a/* x */b/* open") == "ab"
    body = (
        "<style>@import url(a.css); @charset 'x'; line{stroke:#f00} @media print{line{stroke:#00f}} "
        "/* line{stroke:#0f0} */ .c{stroke:#000</style>"
        + BORDER16
        + '<line x1="50" y1="0" x2="50" y2="100"/><line class="c" x1="20" y1="0" x2="20" y2="100"/>'
    )
    drawing = parse_svg_text(HEAD16 + body + "</svg>", "t.svg")
    assert sorted(c.assignment for c in drawing.curves) == ["B", "B", "M"]  # @media ignored, unclosed .c block kept
    assert any("@charset, @import, @media" in w for w in drawing.warnings), drawing.warnings


def test_deep_nesting_is_walked_without_recursion(monkeypatch) -> None:
    """5,000 nested groups (5x Python's recursion limit) read fine once the nesting limit is raised: the walk is
    iterative; with the default limit they are refused with a message naming the variable."""
    text = HEAD16 + "<g>" * 5000 + BORDER16 + '<line x1="50" y1="0" x2="50" y2="100" stroke="red"/>'
    text += "</g>" * 5000 + "</svg>"
    with pytest.raises(PatternError, match=r"nesting depth 65 is above the limit of 64 .*CURVED_FOLD_MAX_NESTING"):
        parse_svg_text(text, "deep.svg")
    monkeypatch.setenv("CURVED_FOLD_MAX_NESTING", "6000")
    drawing = parse_svg_text(text, "deep.svg")
    assert sorted(c.assignment for c in drawing.curves) == ["B", "M"]


def test_element_text_is_linear_and_kept_only_for_style() -> None:
    import time

    t0 = time.perf_counter()
    drawing = parse_svg_text(HEAD16 + "<desc>" + "x\n" * 1_000_000 + "</desc>" + BORDER16 + "</svg>", "t.svg")
    assert time.perf_counter() - t0 < 5.0 and len(drawing.curves) == 1


def test_limits_can_be_raised_by_environment(monkeypatch) -> None:
    many = HEAD16 + BORDER16 + '<line x1="50" y1="0" x2="50" y2="100" stroke="red"/>' * 60 + "</svg>"
    monkeypatch.setenv("CURVED_FOLD_MAX_ELEMENTS", "50")
    with pytest.raises(PatternError, match=r"number of SVG elements 51 is above the limit of 50"):
        parse_svg_text(many, "t.svg")
    monkeypatch.setenv("CURVED_FOLD_MAX_ELEMENTS", "100")
    assert len(parse_svg_text(many, "t.svg").curves) == 61
    path = HEAD16 + BORDER16 + '<path stroke="red" d="M0 0' + " L1 1" * 30 + '"/></svg>'
    monkeypatch.setenv("CURVED_FOLD_MAX_PATH_SEGMENTS", "20")
    with pytest.raises(PatternError, match=r"more than 16 path segments .*CURVED_FOLD_MAX_PATH_SEGMENTS"):
        parse_svg_text(path, "t.svg")


def test_attribute_with_long_whitespace_runs_is_fast() -> None:
    import time

    t0 = time.perf_counter()
    body = BORDER16 + f'<line x1="50{" " * 100_000}x" y1="0" x2="50" y2="100" stroke="red"/>'
    with pytest.raises(PatternError, match=r"attribute x1='50 +\.\.\.' is not a number"):
        parse_svg_text(HEAD16 + body + "</svg>", "t.svg")
    assert time.perf_counter() - t0 < 2.0


# ------------------------------------------------------------------------------------------------ <use> (clones)

XLINK = 'xmlns:xlink="http://www.w3.org/1999/xlink" viewBox="0 0 100 100" width="100mm" height="100mm"'


def test_use_draws_the_element_it_names_moved_by_its_transform_and_x_y() -> None:
    """Inkscape's clones (``<use xlink:href="#id">``, SVG 2's ``href``): the named element is drawn again, moved by
    the use's ``transform`` then ``x``/``y``, inheriting the use's stroke and stroke-opacity where it has none; a
    ``<symbol>`` is drawn where it is used (never in its own place). Found by a helper's 12 petals drawn as 2 paths
    and 10 clones: only the 2 folded, with a warning; now the mesh is the one of the same petals drawn out (205
    vertices, 336 faces)."""
    curves = parse_svg_text(
        svg(
            '<line id="l" stroke="red" x1="10" y1="10" x2="20" y2="10"/>\n'
            '<use xlink:href="#l" transform="rotate(90 10 10)"/>\n'
            '<use href="#l" x="5" y="30"/>\n'
            '<defs><line id="bare" x1="0" y1="0" x2="0" y2="10"/></defs>\n'
            '<use href="#bare" x="50" y="50" stroke="#0000ff" stroke-opacity="0.5"/>\n'
            '<symbol id="s"><line stroke="#000" x1="1" y1="1" x2="2" y2="2"/></symbol>\n'
            '<use href="#s" x="60"/>',
            head=XLINK,
        ),
        "clones.svg",
    ).curves
    ends = [np.round(c.segments[0].points[[0, -1]], 9).tolist() for c in curves]
    assert ends == [
        user([[10, 10], [20, 10]]).tolist(),
        user([[10, 10], [10, 20]]).tolist(),  # rotated a quarter turn about (10, 10)
        user([[15, 40], [25, 40]]).tolist(),
        user([[50, 50], [50, 60]]).tolist(),
        user([[61, 1], [62, 2]]).tolist(),
    ]
    assert [c.assignment for c in curves] == ["M", "M", "M", "V", "B"]
    assert curves[3].fold_angle == pytest.approx(90.0)
    assert curves[2].source == "SVG <line id='l'> (line 2) via <use> (line 4)"


def test_a_nested_svg_is_a_viewport_of_its_own() -> None:
    """``<svg x y width height viewBox>`` inside the drawing places and scales its content (SVG 1.1 §7.9): a tester's
    line at y = 2.5 of ``viewBox="0 0 10 5"`` in the lower half (y 50–100) belongs at y = 75, not 2.5."""
    (_, line) = curves_of(
        '<rect width="100" height="100" fill="none" stroke="#000"/>\n'
        '<svg x="0" y="50" width="100" height="50" viewBox="0 0 10 5">\n'
        '<line id="nested" x1="0" y1="2.5" x2="10" y2="2.5" stroke="#00f" stroke-opacity="0.5"/></svg>'
    )
    np.testing.assert_allclose(line.segments[0].points, user([[0, 75], [100, 75]]), atol=1e-12)


@pytest.mark.parametrize(
    "par,ends",
    [
        ("", [[25, 20], [55, 50]]),  # xMidYMid meet: scale 3, centred in x
        ('preserveAspectRatio="xMinYMax slice"', [[10, -10], [70, 50]]),  # scale 6, bottom-aligned
        ('preserveAspectRatio="none"', [[10, 20], [70, 50]]),  # 6 × 3
        ('preserveAspectRatio="xMaxYMin"', [[40, 20], [70, 50]]),
    ],
)
def test_a_nested_viewport_follows_preserve_aspect_ratio(par: str, ends: list[list[float]]) -> None:
    """A 10 × 10 viewBox in a 60 × 30 viewport at (10, 20): the ends agree with rsvg-convert's rendering."""
    viewport = f'<svg x="10" y="20" width="60" height="30" viewBox="0 0 10 10" {par}>'
    (c,) = curves_of(viewport + '<line stroke="red" x2="10" y2="10"/></svg>')
    np.testing.assert_allclose(c.segments[0].points, user(ends), atol=1e-12)


def test_a_symbol_is_fitted_into_the_size_its_use_gives() -> None:
    """``<symbol viewBox>`` drawn by ``<use width height>`` is scaled into that size (a tester's 10 × 10 pleat on a
    100 × 100 sheet was drawn a tenth of its size in the corner); without a size the use fills 100 % of the
    viewport; a use's width/height also size an ``<svg>`` it draws, and a size of 0 draws nothing."""
    curves = parse_svg_text(
        svg(
            '<defs><symbol id="pleat" viewBox="0 0 10 10"><path d="M 5 0 C 3 3 7 7 5 10" stroke="#00f"/></symbol>\n'
            '<symbol id="wide" viewBox="0 0 20 10" preserveAspectRatio="xMaxYMid meet"><line stroke="red" x2="20" '
            'y2="10"/></symbol><svg id="box" width="10" height="10" viewBox="0 0 1 1"><line stroke="red" x2="1"/>'
            "</svg></defs>\n"
            '<use xlink:href="#pleat" x="0" y="0" width="100" height="100"/>\n'
            '<use href="#wide" x="5" y="5" width="80" height="80"/><use href="#pleat"/>\n'
            '<use href="#box" width="40" height="40"/><use href="#pleat" width="0"/>',
            head=XLINK,
        ),
        "symbols.svg",
    ).curves
    assert len(curves) == 4
    np.testing.assert_allclose(curves[0].segments[0].points, user([[50, 0], [30, 30], [70, 70], [50, 100]]))
    np.testing.assert_allclose(curves[1].segments[0].points, user([[5, 25], [85, 65]]))  # 4×, centred vertically
    np.testing.assert_allclose(curves[2].segments[0].points, curves[0].segments[0].points)  # 100 % of the sheet
    np.testing.assert_allclose(curves[3].segments[0].points, user([[0, 0], [40, 0]]))
    assert curves[0].source == "SVG <path> (line 2) via <use> (line 4)"


def test_a_nested_viewport_without_a_size_is_refused_when_its_viewbox_needs_one() -> None:
    with pytest.raises(PatternError, match=r"SVG <svg id='n'> \(line 2\): its viewBox needs the size of its viewport"):
        parse_svg_text(svg('<svg id="n" viewBox="0 0 1 1"><line stroke="red" x2="1"/></svg>', head=""), "n.svg")


def test_use_that_names_nothing_or_itself_is_skipped_with_a_warning() -> None:
    drawing = parse_svg_text(
        svg(
            '<line id="l" stroke="red" x1="10" y1="10" x2="20" y2="10"/>\n'
            '<use href="#missing"/><use href="l"/>\n'
            '<g id="a"><line stroke="red" x1="30" y1="30" x2="40" y2="30"/><use href="#a" x="1"/></g>\n'
            '<g id="b"><use href="#c" y="5"/></g><g id="c"><use href="#b" y="5"/></g>',
            head=XLINK,
        ),
        "loops.svg",
    )
    assert len(drawing.curves) == 2  # the line and the group's line, each once
    assert "loops.svg: <use> elements that name no element of the file are skipped (line 3)" in drawing.warnings
    assert "loops.svg: <use> elements that would draw themselves again are skipped (lines 4, 5)" in drawing.warnings


def test_nested_uses_cannot_multiply_the_elements_without_bound() -> None:
    """Ten levels of groups that each use the one below ten times would draw 10¹⁰ lines: the elements drawn,
    copies included, count against the element limit, so the file is refused at once in one line."""
    levels = ['<g id="g0"><line stroke="red" x1="1" y1="1" x2="2" y2="1"/></g>']
    for k in range(1, 11):
        levels.append(f'<g id="g{k}">' + "".join(f'<use href="#g{k - 1}" y="{j}"/>' for j in range(10)) + "</g>")
    t0 = time.perf_counter()
    with pytest.raises(PatternError, match=r"deep\.svg \(<use> copies included\): number of SVG elements 50,001"):
        parse_svg_text(svg("\n".join(levels), head=XLINK), "deep.svg")
    assert time.perf_counter() - t0 < 5.0


# ------------------------------------------------------------------------------------------------ hidden elements


def test_hidden_elements_are_not_read_and_a_visible_child_shows_through() -> None:
    """``visibility`` hidden/collapse (attribute, style or CSS) hides shapes as ``display:none`` does, but it is
    inherited and a child may say ``visible`` (SVG 1.1 §11.5). A tester's file kept an old version of a crease in a
    ``<g visibility="hidden">`` and it was folded with the shown one."""
    d = parse_svg_text(
        svg(
            "<style>.gone { visibility: collapse }</style>\n"
            '<line id="shown" stroke="blue" x1="50" y1="0" x2="50" y2="100"/>\n'
            '<g id="old" visibility="hidden"><line id="a" stroke="red" x1="0" y1="50" x2="100" y2="50"/>\n'
            '<line id="back" stroke="red" visibility="visible" x1="0" y1="60" x2="100" y2="60"/></g>\n'
            '<line id="b" stroke="red" style="visibility:hidden" x1="0" y1="70" x2="100" y2="70"/>\n'
            '<line id="c" class="gone" stroke="red" x1="0" y1="80" x2="100" y2="80"/>\n'
            '<g style="visibility:collapse"><g visibility="inherit"><line id="d" stroke="red" x2="1"/></g></g>'
        ),
        "v.svg",
    )
    assert [c.source for c in d.curves] == ["SVG <line id='shown'> (line 3)", "SVG <line id='back'> (line 5)"]
    assert d.warnings == []


def test_current_color_strokes_take_the_color_in_effect() -> None:
    """svgo and icon tools write ``stroke="currentColor"`` with the colour on a group (``<g color="#0000ff">``): the
    valley was skipped as an unknown stroke colour (a designer session). It takes the ``color`` in effect, from an
    attribute, a style or a CSS rule, inherited; black where none is set."""
    svg = (
        '<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="200mm" viewBox="0 0 200 200" fill="none">'
        "<style>.m { color: #ff0000 }</style>"
        '<rect width="200" height="200" stroke="currentColor"/>'
        '<g color="#0000ff"><path d="M150,0 C130,70 170,130 150,200" stroke="currentColor" stroke-opacity="0.5"/></g>'
        '<g class="m"><path d="M50,0 L50,200" stroke="currentColor"/></g>'
        '<path d="M100,0 L100,200" style="color: blue; stroke: currentcolor"/>'
        "</svg>"
    )
    drawing = parse_svg_text(svg, "cc.svg")
    got = sorted((c.assignment, round(c.fold_angle or 0.0, 6)) for c in drawing.curves)
    assert got == [("B", 0.0), ("M", -180.0), ("V", 90.0), ("V", 180.0)]
    assert not any("unknown stroke" in w for w in drawing.warnings)
