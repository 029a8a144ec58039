"""Property-based fuzzing of the whole engine: random Bézier creases in random borders, random roles and angles.

Every generated pattern must end in exactly one of two ways:

* **folded**: a mesh whose folded coordinates are finite, no larger than the flat sheet's diagonal, with the
  per-node strain below :data:`STRAIN_BOUND_PCT` and a bounded iteration count; or
* **rejected** with a catalogued :class:`PatternError` (a message from ``docs/errors.md``, see :data:`CATALOGUE`).

Anything else (another exception type, an uncatalogued message, non-finite output, a run over :data:`TIME_BOUND_S`)
fails. The CI profile (``test_fuzz_quick``) is bounded to about a minute; the long run is
``.venv/bin/python tools/fuzz_long.py --examples 2000`` (counts in docs/errors.md).
"""

from __future__ import annotations

import json
import math
import re
import time
import warnings
from collections import Counter
from dataclasses import dataclass

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from curved_fold.core.pattern.discretize import discretize
from curved_fold.core.pattern.model import CreaseCurve, CurveSegment, PatternError
from curved_fold.core.pipeline import fold_pattern
from curved_fold.core.solve.solver import SolverError, SolverSettings

STRAIN_BOUND_PCT = 100.0
"""Largest per-node strain (Origami Simulator's mean |ℓ/L0 − 1| of a node's bars, percent) a folded result may
show. Patterns that cannot fold as assigned stretch (the paper's Fig. 7 reports this), but a sheet whose bars
doubled in length has exploded."""

TIME_BOUND_S = 60.0
"""Wall-time bound of one pattern (discretise + mesh + fold) on the shared 2-core CI machine."""

CATALOGUE: dict[str, str] = {
    "border crosses itself": r"the border crosses or touches itself at \(",
    "no border": r"crease pattern has no border \(B\) segments",
    "no paper": r"triangulation: no paper left: the border does not enclose any region",
    "collinear": r"triangulation: all pattern vertices lie on one line",
    "all segments degenerate": r"crease pattern: every segment is shorter than the merge tolerance",
    "segments cross (triangulation)": r"triangulation: (segments|pattern edges .* and .*) cross or touch near \(",
    "edge not in triangulation": r"triangulation: pattern edge \d+ \(.*\) is not an edge of the triangulation",
    "vertex not in triangulation": r"triangulation: pattern vertex \d+ at \[.*\] mm is not in the triangulation",
    "degenerate triangle": r"(triangle \d+ .* is degenerate|has zero length)",
    "absurd coordinates": r"coordinate .* mm in a \w+ segment is beyond|an arc with centre or radius .* mm is beyond",
    "microscopic sheet": r"the sheet is only .* mm across \(minimum",
}
"""Catalogued rejections (docs/errors.md): a short name → the regular expression its message must match."""


@dataclass
class Outcome:
    """What one fuzzed pattern did: ``kind`` is ``"folded"`` or ``"rejected"``; ``detail`` the catalogue name."""

    kind: str
    detail: str
    faces: int = 0
    strain_max_pct: float = 0.0
    iterations: int = 0
    seconds: float = 0.0
    does_not_fold: bool = False


def _line(a, b) -> CurveSegment:
    return CurveSegment("line", np.array([a, b], dtype=float))


def _cubic(points) -> CurveSegment:
    return CurveSegment("cubic", np.asarray(points, dtype=float).reshape(4, 2))


unit = st.floats(min_value=0.0, max_value=1.0, allow_nan=False)


@st.composite
def borders(draw) -> tuple[CreaseCurve, float]:
    """A random sheet outline and its size (mm): rectangle, star-shaped polygon, or a wobbly closed Bézier loop."""
    size = draw(st.sampled_from([1.0, 20.0, 150.0, 600.0, 150.0, 150.0, 1e-4, 1e9]))
    kind = draw(st.sampled_from(["rectangle", "polygon", "bezier"]))
    if kind == "rectangle":
        aspect = draw(st.floats(min_value=0.05, max_value=1.0))
        w, h = size, size * aspect
        c = [(0, 0), (w, 0), (w, h), (0, h)]
        segs = [_line(c[i], c[(i + 1) % 4]) for i in range(4)]
    else:
        n = draw(st.integers(min_value=3, max_value=7))
        # angles in increasing order and radii in [0.3, 1]: a star-shaped (simple) polygon around the centre
        gaps = np.array(draw(st.lists(st.floats(0.2, 1.0), min_size=n, max_size=n)))
        ang = 2 * np.pi * np.cumsum(gaps) / gaps.sum()
        rad = 0.5 * size * np.array(draw(st.lists(st.floats(0.3, 1.0), min_size=n, max_size=n)))
        pts = np.column_stack([rad * np.cos(ang), rad * np.sin(ang)]) + 0.5 * size
        if kind == "polygon":
            segs = [_line(pts[i], pts[(i + 1) % n]) for i in range(n)]
        else:  # each side bulges out by a random amount: may self-intersect (a catalogued rejection)
            bulge = draw(st.lists(st.floats(-0.4, 0.6), min_size=n, max_size=n))
            segs = []
            for i in range(n):
                a, b = pts[i], pts[(i + 1) % n]
                normal = np.array([b[1] - a[1], a[0] - b[0]])
                p1 = a + (b - a) / 3 + bulge[i] * normal
                p2 = a + 2 * (b - a) / 3 + bulge[i] * normal
                segs.append(_cubic([a, p1, p2, b]))
    return CreaseCurve(segs, "B", None, closed=True, source=f"fuzz border ({kind})"), size


@st.composite
def crease_patterns(draw) -> list[CreaseCurve]:
    """A random border with 1–5 random creases: cubic or straight, ends anywhere in (or a little past) the sheet,
    random role (mountain, valley, facet, undriven, cut) and angle (none, or any in ±180°).

    Now and then the input is damaged the ways designers damage it: the border is left out or left open, a crease
    is drawn twice, a crease collapses to a point, the sheet is microscopic or absurdly large (sizes above)."""
    border, size = draw(borders())
    damage = draw(st.sampled_from(["none"] * 6 + ["no border", "open border", "duplicate", "point"]))
    if damage == "no border":
        curves = []
    elif damage == "open border" and len(border.segments) > 1:
        curves = [CreaseCurve(border.segments[:-1], "B", None, closed=False, source=border.source + " (open)")]
    else:
        curves = [border]
    for k in range(draw(st.integers(min_value=1, max_value=5))):

        def point():
            return [(-0.1 + 1.2 * draw(unit)) * size, (-0.1 + 1.2 * draw(unit)) * size]

        if draw(st.booleans()):
            seg = _cubic([point(), point(), point(), point()])
        else:
            seg = _line(point(), point())
        role = draw(st.sampled_from(["M", "V", "M", "V", "F", "U", "C"]))
        angle = draw(st.one_of(st.none(), st.floats(min_value=-180.0, max_value=180.0)))
        if role == "F":
            angle = 0.0
        elif role in ("U", "C"):
            angle = None
        curves.append(CreaseCurve([seg], role, angle, source=f"fuzz crease {k}"))
    if damage == "duplicate":
        twin = curves[-1]
        curves.append(CreaseCurve(list(twin.segments), draw(st.sampled_from(["M", "V"])), None, source="fuzz twin"))
    elif damage == "point":
        p = np.full((4, 2), 0.5 * size)
        curves.append(CreaseCurve([_cubic(p)], "V", 90.0, source="fuzz point"))
    return curves


def classify_error(message: str) -> str | None:
    """The catalogue name a :class:`PatternError` message belongs to, or ``None`` if it is not catalogued."""
    for name, pattern in CATALOGUE.items():
        if re.search(pattern, message):
            return name
    return None


def flat_path_length(mesh, a: int, b: int) -> float:
    """Length of the shortest path along mesh edges from vertex ``a`` to ``b`` on the flat sheet (Dijkstra; infinite
    between pieces a cut separates). Folding cannot move two points of paper farther apart than a path on it, up to
    the strain: the bound of the fuzz run's "grew" check. The flat diagonal was used before, and a piece cut into a
    U by a curved cut (seed 43) opened to 1.1 times it, as paper may."""
    import heapq

    length = np.linalg.norm(mesh.vertices[mesh.edges[:, 1]] - mesh.vertices[mesh.edges[:, 0]], axis=1)
    neighbours: dict[int, list[tuple[int, float]]] = {}
    for (i, j), w in zip(mesh.edges.tolist(), length.tolist(), strict=True):
        neighbours.setdefault(i, []).append((j, w))
        neighbours.setdefault(j, []).append((i, w))
    best = {a: 0.0}
    queue = [(0.0, a)]
    while queue:
        d, v = heapq.heappop(queue)
        if v == b:
            return d
        if d > best.get(v, math.inf):
            continue
        for u, w in neighbours.get(v, []):
            if d + w < best.get(u, math.inf):
                best[u] = d + w
                heapq.heappush(queue, (d + w, u))
    return math.inf


def fold_outcome(curves: list[CreaseCurve], *, angle: float = 90.0, time_limit: float = 30.0) -> Outcome:
    """Discretise, mesh and fold ``curves``; check the result and return what happened (raises on a violation)."""
    t0 = time.perf_counter()
    try:
        pattern = discretize(curves)
        run = fold_pattern(pattern, angle=angle, settings=SolverSettings(time_limit=time_limit))
    except (PatternError, SolverError) as exc:
        name = classify_error(str(exc))
        assert name is not None, f"uncatalogued {type(exc).__name__}: {exc}"
        return Outcome("rejected", name, seconds=time.perf_counter() - t0)
    seconds = time.perf_counter() - t0
    pos = run.result.positions
    report = run.report
    assert np.all(np.isfinite(pos)), "non-finite folded coordinates"
    stretch = 1.01 * (1.0 + report["strain_max_pct"] / 100.0)
    for k in range(3):  # the two vertices farthest apart along each axis: no farther than a path on the flat sheet
        a, b = int(np.argmin(pos[:, k])), int(np.argmax(pos[:, k]))
        apart = float(np.linalg.norm(pos[b] - pos[a]))
        assert apart <= stretch * flat_path_length(run.mesh, a, b) + 1e-9 * run.mesh.diagonal, "the sheet grew"
    assert math.isfinite(report["strain_max_pct"]) and report["strain_max_pct"] < STRAIN_BOUND_PCT, report
    assert report["iterations"] <= SolverSettings().max_iterations
    assert seconds < TIME_BOUND_S, f"one pattern took {seconds:.1f} s"
    detail = "does not fold as assigned" if report["does_not_fold_as_assigned"] else "folded"
    if not report["converged"]:
        message = report["message"]
        why = "stalled" if message.startswith("stalled") else "time limit" if "time limit" in message else "cap"
        detail += f" (not converged: {why}, residual given)"
        assert "residual" in message, message
    return Outcome(
        "folded",
        detail,
        faces=int(report["faces"]),
        strain_max_pct=float(report["strain_max_pct"]),
        iterations=int(report["iterations"]),
        seconds=seconds,
        does_not_fold=bool(report["does_not_fold_as_assigned"]),
    )


QUICK_COUNTS: Counter[str] = Counter()


@settings(
    max_examples=40,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(curves=crease_patterns())
def test_fuzz_quick(curves: list[CreaseCurve]) -> None:
    """CI profile: 40 derandomised patterns (same ones every run), about 30 s on the CI machine."""
    out = fold_outcome(curves)
    QUICK_COUNTS[f"{out.kind}: {out.detail}"] += 1


def test_an_unconverged_fold_is_labelled_with_why_it_stopped() -> None:
    """A fold stopped by its time limit is counted as "not converged: time limit" (a stall or the iteration cap get
    their own labels, read from the solver's message)."""
    c = [(0.0, 0.0), (100.0, 0.0), (100.0, 60.0), (0.0, 60.0)]
    border = CreaseCurve([_line(c[i], c[(i + 1) % 4]) for i in range(4)], "B", None, closed=True, source="border")
    crease = CreaseCurve([_cubic([(20, 0), (40, 20), (60, 40), (80, 60)])], "V", 90.0, closed=False, source="crease")
    out = fold_outcome([border, crease], time_limit=0.0)
    assert out.kind == "folded" and out.detail.endswith("(not converged: time limit, residual given)"), out.detail
    assert fold_outcome([border, crease]).detail == "folded"


def test_classify_error_knows_the_catalogue() -> None:
    assert classify_error("the border crosses or touches itself at (1.0, 2.0) mm (x)") == "border crosses itself"
    assert classify_error("triangulation: no paper left: the border does not enclose any region") == "no paper"
    assert classify_error("something new went wrong") is None


# ------------------------------------------------------------------------------------------------ file readers
#
# Property-based fuzz of the two text readers (issue 16): any FOLD JSON and any SVG text, however wrong its types,
# nesting or sizes, must either be read or be refused with one PatternError, never another exception.

from curved_fold.core.io.fold import parse_fold, pattern_for_folding  # noqa: E402
from curved_fold.core.io.svg import parse_svg_text  # noqa: E402

FOLD_KEYS = [
    "vertices_coords",
    "edges_vertices",
    "edges_assignment",
    "edges_foldAngle",
    "edges_foldAngles",
    "faces_vertices",
    "file_frames",
    "frame_unit",
    "frame_parent",
    "frame_inherit",
    "curved_fold:flat_coords",
    "curved_fold:edge_polyline",
    "curved_fold:edge_from_curve",
    "curved_fold:sources",
    "curved_fold:warnings",
    "curved_fold:fold_angles",
    "curved_fold:mesh_type",
]

json_scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(10**30), max_value=10**30),
    st.sampled_from([0, 1, 2, 3, -1, 4, 1.5, 1e308, -1e308, 10**400, 180, 181, -540]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(["B", "M", "V", "F", "U", "C", "b", "x", "", "1", "mm", "cm", "in", "unit", "ruling"]),
)
json_values = st.recursive(
    json_scalars,
    lambda children: st.one_of(
        st.lists(children, max_size=6),
        st.dictionaries(st.sampled_from(FOLD_KEYS + ["x", "frame_classes"]), children, max_size=4),
    ),
    max_leaves=40,
)


@st.composite
def fold_documents(draw) -> str:
    """FOLD text: a valid square crease pattern with some fields replaced by anything (wrong types, nesting,
    out-of-range numbers, huge integers), some dropped, or the text cut or nested deeply."""
    n = draw(st.integers(min_value=0, max_value=6))
    coords = [[float(i % 3), float(i // 3)] for i in range(n)]
    doc: dict = {
        "vertices_coords": coords,
        "edges_vertices": [[i, (i + 1) % max(n, 1)] for i in range(n)],
        "edges_assignment": ["B"] * n,
    }
    for key in draw(st.lists(st.sampled_from(FOLD_KEYS), max_size=4)):
        if draw(st.booleans()):
            doc[key] = draw(json_values)
        else:
            doc.pop(key, None)
    text = json.dumps(doc, allow_nan=True) if draw(st.integers(0, 9)) else "[" * draw(st.sampled_from([1, 900, 5000]))
    mode = draw(st.sampled_from(["whole"] * 8 + ["cut", "nest"]))
    if mode == "cut":
        text = text[: draw(st.integers(min_value=0, max_value=len(text)))]
    elif mode == "nest":
        depth = draw(st.sampled_from([1, 70, 400, 1200, 3000]))
        text = '{"x": ' + "[" * depth + "]" * depth + ', "vertices_coords": []}'
    return text


def read_fold_text(text: str) -> str:
    """Read FOLD text as the command line does; returns "read" or "refused" (any other exception propagates)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)  # a numpy overflow warning would reach the user too
            doc = parse_fold(text, "fuzz.fold")
            if doc.vertices is not None:
                pattern_for_folding(doc)
    except PatternError:
        return "refused"
    return "read"


SVG_TAGS = ["g", "path", "line", "rect", "circle", "ellipse", "polyline", "polygon", "style", "desc", "defs", "use"]
SVG_ATTRS = {
    "d": [
        *("M0 0 L10 10", "M 0,0 C 1 2 3 4 5 6 Z", "m1 1 a5 5 0 1 0 10 0", "M0 0 Q", "L1 1", "M1e400 0", "M0 0 H"),
        "M0 0 A 1e300 1e300 0 0 1 1 1",
    ],
    "transform": [
        *("scale(2)", "rotate(30 1 2)", "matrix(1 0 0 1 0 0)", "skewX(90)", "scale(1e308)", "scale(1e200)"),
        "bad(1)",
    ],
    "stroke": ["#000", "red", "#0000ff", "rgb(0,255,0)", "yellow", "#f0f", "none", "inherit", "#12"],
    "style": ["stroke:#f00", "stroke:red;opacity:0.5", "display:none", "opacity:nan", ";;:", "stroke-opacity:2"],
    "opacity": ["0.5", "-1", "1e400", "x", "50%"],
    "points": ["0,0 10,10 20 0", "1 2 3", "a b", ""],
    "x1": ["0", "1e400", "5px", "x"],
    "width": ["10", "0", "-5", "1e9", "nan"],
    "height": ["10", "0", "1e-9"],
    "r": ["5", "0", "-1"],
    "class": ["a", "b c"],
    "id": ["a", "b"],
    "href": ["#a", "#b", "#missing", "a"],
}
CSS_TEXTS = [
    "a{",
    "line{stroke:#00f}",
    "@import url(x.css); path{stroke:red}",
    "/* open",
    "}}{{",
    ".a{stroke:#000}",
    "@media print{line{stroke:red}}",
    "#b,g>line{stroke:blue}",
]


@st.composite
def svg_documents(draw) -> str:
    """SVG text: random trees (deep nesting included) of shapes and containers with attributes drawn from good and
    bad values, random stylesheets, and now and then a DOCTYPE with entities or a cut document."""
    depth_limit = draw(st.sampled_from([3, 3, 3, 80]))

    def element(depth: int) -> str:
        tag = draw(st.sampled_from(SVG_TAGS))
        keys = draw(st.lists(st.sampled_from(sorted(SVG_ATTRS)), max_size=4, unique=True))
        attrs = "".join(f' {k}="{draw(st.sampled_from(SVG_ATTRS[k]))}"' for k in keys)
        if tag == "style":
            return f"<style>{''.join(draw(st.lists(st.sampled_from(CSS_TEXTS), max_size=4)))}</style>"
        if tag in ("g", "defs") and depth < depth_limit:
            n = 1 if depth_limit > 3 else draw(st.integers(0, 3))
            return f"<{tag}{attrs}>" + "".join(element(depth + 1) for _ in range(n)) + f"</{tag}>"
        return f"<{tag}{attrs}/>"

    body = '<rect x="0" y="0" width="100" height="100" stroke="#000" fill="none"/>' if draw(st.booleans()) else ""
    body += "".join(element(0) for _ in range(draw(st.integers(1, 5))))
    if draw(st.integers(0, 9)) == 0:  # deep nesting, beyond Python's recursion limit
        deep = draw(st.sampled_from([3000, 1200, 70]))
        body = "<g>" * deep + body + "</g>" * deep
    head = ""
    if draw(st.integers(0, 9)) == 0:
        head = '<!DOCTYPE svg [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">]>'
        body += "<title>&b;&b;</title>"
    size = draw(st.sampled_from(['width="100mm" height="100mm" viewBox="0 0 100 100"', "", 'viewBox="0 0 0 1"']))
    text = f'{head}<svg xmlns="http://www.w3.org/2000/svg" {size}>{body}</svg>'
    if draw(st.integers(0, 9)) == 0:
        text = text[: draw(st.integers(min_value=0, max_value=len(text)))]
    return text


def read_svg_text(text: str) -> str:
    """Read SVG text and discretise its curves as the command line does; returns "read" or "refused"."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)  # a numpy overflow warning would reach the user too
            drawing = parse_svg_text(text, "fuzz.svg")
            discretize(drawing.curves)
    except PatternError:
        return "refused"
    return "read"


READER_SETTINGS = settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much],
)


@READER_SETTINGS
@given(text=fold_documents())
def test_fuzz_fold_reader(text: str) -> None:
    """CI profile: 150 derandomised FOLD documents, each read or refused with a PatternError."""
    t0 = time.perf_counter()
    read_fold_text(text)
    assert time.perf_counter() - t0 < 10.0


@READER_SETTINGS
@given(text=svg_documents())
def test_fuzz_svg_reader(text: str) -> None:
    """CI profile: 150 derandomised SVG documents, each read (and discretised) or refused with a PatternError."""
    t0 = time.perf_counter()
    read_svg_text(text)
    assert time.perf_counter() - t0 < 10.0
