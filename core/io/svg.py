"""Read crease patterns drawn in Origami Simulator's SVG convention (origami-simulator-model.md §5.1, §5.4, §6).

Blender's own SVG importer drops stroke colours, so the file is parsed here with :mod:`xml.parsers.expat`, keeping
the source line of every element for messages (``SVG <path id='p3'> (line 12)``).

What is read:

* elements ``path`` (every command M L H V C S Q T A Z, absolute and relative, implicit repeats, smooth-control
  reflection, several sub-paths), ``line``, ``polyline``, ``polygon``, ``rect`` (rounded corners become arcs),
  ``circle`` and ``ellipse``; contents of ``defs``/``symbol``/``clipPath``/``mask``/``metadata``/... are skipped;
* nested ``transform`` lists (``matrix translate scale rotate skewX skewY``), applied innermost first;
* viewports: a nested ``<svg>`` (``x y width height viewBox preserveAspectRatio``, sizes 100 % by default) and a
  ``<symbol viewBox>`` drawn by a ``<use width height>`` place and scale their content as the root's viewBox does
  (nothing is clipped to them);
* clones: ``<use href="#id">`` (or ``xlink:href``) draws the element it names (a ``<symbol>`` too) moved by its
  ``transform`` then ``x``/``y``, inheriting the use's stroke; a use that names nothing or would draw itself again
  is skipped with a warning, and the copies count against the element limit (nested uses cannot multiply them);
* the stroke colour, which gives the assignment by EXACT match with Origami Simulator's table (any CSS spelling of
  those rgb values: keywords, 3/4/6/8-digit hex, ``rgb()``/``rgba()``/``hsl()``/``hsla()`` with commas or spaces,
  numbers or percentages); ``opacity × stroke-opacity × alpha × 180°`` gives the fold angle (mountain negative),
  the alpha of the colour (``rgba(255,0,0,0.6)``, ``#ff000099``) counting as stroke-opacity does;
* presentation attributes < ``<style>`` rules (type, ``.class``, ``#id`` selectors, comma lists) < inline ``style``;
  ``stroke``/``stroke-opacity`` inherit from ancestors, ``opacity`` is the element's own;
* hidden elements are not read: ``display:none`` (the element and everything in it) and ``visibility`` ``hidden`` or
  ``collapse`` (inherited, so a child that says ``visible`` is read, as SVG draws it);
* units: ``viewBox`` with ``width``/``height`` in physical units give the user unit → mm scale; otherwise one user
  unit is one CSS px = 25.4/96 mm. Shape attributes take user units, CSS absolute lengths (96 px = 1 in, before
  the viewBox scales them) or percentages of the viewport. Points are then mapped (x, y) → (x, −y) so the sheet
  is y-up in mm.

Each sub-path (or element) becomes one :class:`~.pattern.CreaseCurve` of exact segments: quadratic Béziers are
degree-elevated to cubics, elliptical arcs stay arcs (an affine image of an ellipse is recomputed exactly).

Hostile files are read in bounded time and memory: text is kept only inside ``<style>`` (gathered in a list and
joined once), the CSS and comment scanners are single passes (no backtracking regular expression), the tree is
walked with an explicit stack, and the file size, element count, nesting depth and number of path segments are
limited (:mod:`.limits`, each raised by an environment variable named in the message).
"""

from __future__ import annotations

import math
import re
import xml.parsers.expat
from collections.abc import Generator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import run_to_end
from ..pattern.model import CreaseCurve, CurveSegment, PatternError
from . import limits

PX_MM = 25.4 / 96.0
"""Millimetres per CSS pixel (one SVG user unit when the file gives no physical size)."""

UNIT_MM = {
    "": PX_MM,
    "px": PX_MM,
    "mm": 1.0,
    "cm": 10.0,
    "in": 25.4,
    "pt": 25.4 / 72.0,
    "pc": 25.4 / 6.0,
    "q": 0.25,
}
"""Millimetres per unit for every length unit SVG allows on ``width``/``height``."""

ASSIGNMENT_RGB = {
    (0, 0, 0): "B",
    (255, 0, 0): "M",
    (0, 0, 255): "V",
    (0, 255, 0): "C",
    (255, 255, 0): "F",
    (255, 0, 255): "U",
}
"""Origami Simulator's exact stroke colours (§5.1) → FOLD assignment."""

NAMED_COLOURS = {
    "black": (0, 0, 0),
    "red": (255, 0, 0),
    "blue": (0, 0, 255),
    "lime": (0, 255, 0),
    "yellow": (255, 255, 0),
    "magenta": (255, 0, 255),
    "fuchsia": (255, 0, 255),
    "white": (255, 255, 255),
    "gray": (128, 128, 128),
    "grey": (128, 128, 128),
    "silver": (192, 192, 192),
    "maroon": (128, 0, 0),
    "navy": (0, 0, 128),
    "purple": (128, 0, 128),
    "olive": (128, 128, 0),
    "teal": (0, 128, 128),
    "aqua": (0, 255, 255),
    "cyan": (0, 255, 255),
    "orange": (255, 165, 0),
}
"""CSS colour keywords that matter here (the six of the table, and common ones so warnings stay readable)."""

LITERAL_ASSIGNMENTS = {"green": "C"}
"""Spellings Origami Simulator's table accepts literally although CSS maps them elsewhere (``green`` is 0,128,0)."""

SKIPPED_CONTAINERS = {
    "defs",
    "symbol",
    "clipPath",
    "mask",
    "metadata",
    "title",
    "desc",
    "pattern",
    "marker",
    "linearGradient",
    "radialGradient",
    "filter",
    "style",
    "script",
    "text",
    "foreignObject",
    "namedview",
}
"""Elements whose contents never draw creases."""

ANGLE_HINT = "set stroke-opacity (or opacity) to the fold angle / 180° (0.6 for 108°)"
"""How a stroke gets its fold angle, for the warnings about opacities that give none."""

SHAPES = {"path", "line", "polyline", "polygon", "rect", "circle", "ellipse"}
SAMPLED_ATTRIBUTE, SAMPLED_VALUE = "data-curved-fold", "sampled"
"""How Curved Fold's SVG export marks its polylines (a curve's samples, a border's subdivision, as meshed): read
back, their vertices are kept as written (:attr:`..pattern.model.CreaseCurve.sampled`), not thinned as a polyline
drawn far finer than the interval is, so the file folds to the mesh it was written from."""
INHERITED = ("stroke", "stroke-opacity", "fill", "display", "visibility", "color")


VISITS_PER_UNIT = 250
"""Elements read per unit of work (:func:`parse_svg_steps`): ~6 ms on CircularPleat-antiFacet's lines, so a
Blender import's slices stay short on files of tens of thousands of elements."""


@dataclass
class SvgDrawing:
    """What :func:`read_svg` found: one crease curve per element/sub-path with a known colour, in mm (y up).

    ``width_mm``/``height_mm`` are the drawing's viewport size; ``warnings`` lists what was skipped and why.
    """

    curves: list[CreaseCurve]
    warnings: list[str] = field(default_factory=list)
    width_mm: float = 0.0
    height_mm: float = 0.0
    source_name: str = ""


# ----------------------------------------------------------------------------------------------------- XML tree


@dataclass
class _Element:
    tag: str
    attrib: dict[str, str]
    line: int
    children: list[_Element] = field(default_factory=list)
    text: str = ""


def _local(name: str) -> tuple[str, bool]:
    """Local part of an expat ``uri}local`` name, and whether it was namespaced."""
    if "}" in name:
        return name.rsplit("}", 1)[1], True
    return name, False


def _parse_xml(text: str | bytes, source_name: str) -> _Element:
    """Parse XML into a light tree that remembers the line number of every start tag."""
    parser = xml.parsers.expat.ParserCreate(namespace_separator="}")
    stack: list[_Element] = []
    root: list[_Element] = []
    texts: list[list[str] | None] = []  # per open element: its text pieces (``<style>`` only), joined at the end tag
    max_elements, max_depth = limits.SVG_ELEMENTS.value, limits.NESTING.value
    count = 0

    def start(name: str, attrs: dict[str, str]) -> None:
        nonlocal count
        count += 1
        if count > max_elements:
            limits.SVG_ELEMENTS.check(count, f"{source_name} (line {parser.CurrentLineNumber})")
        if len(stack) >= max_depth:
            limits.NESTING.check(len(stack) + 1, f"{source_name} (line {parser.CurrentLineNumber})")
        tag, _ = _local(name)
        attrib = {}
        for key, value in attrs.items():
            local, namespaced = _local(key)
            attrib[key if namespaced else local] = value
        if name.startswith("http://www.w3.org/2000/svg}") or "}" not in name:
            elem = _Element(tag, attrib, parser.CurrentLineNumber)
        else:  # foreign namespace (sodipodi:namedview, rdf, ...): keep it out of the drawing
            elem = _Element("#foreign:" + tag, attrib, parser.CurrentLineNumber)
        if stack:
            stack[-1].children.append(elem)
        else:
            root.append(elem)
        stack.append(elem)
        texts.append([] if elem.tag == "style" else None)

    def end(name: str) -> None:
        elem, pieces = stack.pop(), texts.pop()
        if pieces:
            elem.text = "".join(pieces)

    def chars(data: str) -> None:
        if texts and texts[-1] is not None:
            texts[-1].append(data)

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as exc:
        raise PatternError(
            f"{source_name}: malformed XML at line {exc.lineno}, column {exc.offset + 1}: "
            f"{xml.parsers.expat.ErrorString(exc.code)}"
        ) from None
    if not root:
        raise PatternError(f"{source_name}: no XML element found")
    return root[0]


# ----------------------------------------------------------------------------------------------------- CSS


def _strip_comments(text: str) -> str:
    """``text`` without ``/* ... */`` comments (an unclosed one runs to the end), in one pass."""
    out: list[str] = []
    pos = 0
    while True:
        i = text.find("/*", pos)
        if i < 0:
            out.append(text[pos:])
            break
        out.append(text[pos:i])
        j = text.find("*/", i + 2)
        if j < 0:
            break
        pos = j + 2
    return "".join(out)


def _css_blocks(text: str) -> list[tuple[str, str]]:
    """(prelude, body) of every top-level ``prelude { body }`` block, in one pass over the braces.

    Nested blocks (``@media { a { } }``) stay inside their parent's body; a block left open at the end of the
    sheet is closed there (as CSS does); stray ``}`` are ignored.
    """
    blocks: list[tuple[str, str]] = []
    depth = 0
    start = body_start = 0
    prelude = ""
    for m in re.finditer(r"[{}]", text):
        if m.group() == "{":
            if depth == 0:
                prelude, body_start = text[start : m.start()], m.end()
            depth += 1
        elif depth == 0:
            start = m.end()
        else:
            depth -= 1
            if depth == 0:
                blocks.append((prelude, text[body_start : m.start()]))
                start = m.end()
    if depth:
        blocks.append((prelude, text[body_start:]))
    return blocks


_SIMPLE_SELECTOR = re.compile(r"^(?P<type>[A-Za-z][\w-]*|\*)?(?P<rest>(?:[.#][\w-]+)*)$")


@dataclass
class _Rule:
    type: str | None
    classes: tuple[str, ...]
    ident: str | None
    specificity: tuple[int, int, int]
    order: int
    declarations: dict[str, str]


def _parse_declarations(text: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for part in text.split(";"):
        if ":" in part:
            key, value = part.split(":", 1)
            value = value.replace("!important", "").strip()
            out[key.strip().lower()] = value
    return out


def _parse_stylesheet(text: str, warnings: list[str], where: str) -> list[_Rule]:
    """Rules of a ``<style>`` sheet; selectors other than simple ``type.class#id`` ones are skipped with a warning."""
    rules: list[_Rule] = []
    text = _strip_comments(text.replace("<![CDATA[", "").replace("]]>", ""))
    skipped: list[str] = []
    at_rules: list[str] = []
    for prelude, body in _css_blocks(text):
        # statement at-rules (``@import url(x.css);``) end with ';' and belong to no block: skip them, not the rule
        *statements, selectors = prelude.split(";")
        at_rules += [st.strip().split(None, 1)[0] for st in statements if st.strip().startswith("@")]
        if selectors.strip().startswith("@"):
            at_rules.append(selectors.strip().split(None, 1)[0])
            continue
        decls = _parse_declarations(body)
        for sel in selectors.split(","):
            sel = sel.strip()
            m = _SIMPLE_SELECTOR.match(sel)
            if not sel or not m:
                skipped.append(sel)
                continue
            type_ = m.group("type")
            rest = m.group("rest")
            classes = tuple(re.findall(r"\.([\w-]+)", rest))
            ids = re.findall(r"#([\w-]+)", rest)
            spec = (len(ids), len(classes), 1 if type_ and type_ != "*" else 0)
            rules.append(
                _Rule(
                    None if type_ in (None, "*") else type_,
                    classes,
                    ids[0] if ids else None,
                    spec,
                    len(rules),
                    decls,
                )
            )
    if skipped:
        shown = sorted(set(skipped))
        more = f", ... ({len(shown) - 8} more)" if len(shown) > 8 else ""
        warnings.append(f"{where}: CSS selectors not supported (rules ignored): {', '.join(shown[:8])}{more}")
    if at_rules:
        warnings.append(f"{where}: CSS at-rules not followed: {', '.join(sorted(set(at_rules))[:8])}")
    return rules


def _matches(rule: _Rule, elem: _Element) -> bool:
    if rule.type is not None and rule.type != elem.tag:
        return False
    if rule.ident is not None and elem.attrib.get("id") != rule.ident:
        return False
    if rule.classes:
        have = set(elem.attrib.get("class", "").split())
        if not set(rule.classes) <= have:
            return False
    return True


def _own_style(elem: _Element, rules: list[_Rule]) -> dict[str, str]:
    """The element's own declared properties: attributes < matching CSS rules (by specificity, order) < ``style``."""
    props: dict[str, str] = {}
    for key in ("stroke", "stroke-opacity", "fill", "opacity", "display", "visibility", "color"):
        if key in elem.attrib:
            props[key] = elem.attrib[key].strip()
    for rule in sorted((r for r in rules if _matches(r, elem)), key=lambda r: (r.specificity, r.order)):
        props.update(rule.declarations)
    if "style" in elem.attrib:
        props.update(_parse_declarations(elem.attrib["style"]))
    return props


# ----------------------------------------------------------------------------------------------------- colours


_NUMBER_TEXT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_NUMBER = re.compile(_NUMBER_TEXT)
_QUANTITY = re.compile(rf"({_NUMBER_TEXT})\s*([A-Za-z%]*)")
"""A number and its unit (letters or ``%``, maybe none), as CSS writes lengths, percentages and angles."""

_HUE_UNITS = {"": 1.0, "deg": 1.0, "grad": 0.9, "rad": 180.0 / math.pi, "turn": 360.0}
"""Degrees per unit of an ``hsl()`` hue."""


def _css_number(text: str, full: float, units: dict[str, float] | None = None) -> float | None:
    """A finite CSS number (lower case), a percentage of ``full``, or a number with one of ``units`` (value per
    unit); else None."""
    m = _QUANTITY.fullmatch(text)
    if not m or not math.isfinite(x := float(m.group(1))):
        return None
    unit = m.group(2)
    if unit == "%":
        return x * full / 100.0
    scale = (units or {"": 1.0}).get(unit)
    return None if scale is None else x * scale


def _colour_arguments(body: str) -> tuple[list[str], str] | None:
    """The three channels and the alpha ("1" if none) of ``rgb()``/``hsl()`` in the comma syntax ``0, 0, 255, 0.5``
    or the space syntax of CSS Color 4 ``0 0 255 / 50%``; None if it is neither."""
    if "," in body:
        parts = [p.strip() for p in body.split(",")]
        return (parts[:3], parts[3] if len(parts) == 4 else "1") if len(parts) in (3, 4) and "/" not in body else None
    channels, slash, alpha = body.partition("/")
    parts = channels.split()
    if len(parts) != 3 or (slash and len(alpha.split()) != 1):
        return None
    return parts, alpha.strip() if slash else "1"


def _hsl_rgb(h: float, s: float, lightness: float) -> tuple[float, float, float]:
    """sRGB channels (0–255) of an HSL colour, by CSS Color 4's formula (hue in degrees, s and l from 0 to 1)."""
    s, lightness = min(max(s, 0.0), 1.0), min(max(lightness, 0.0), 1.0)
    a = s * min(lightness, 1.0 - lightness)

    def channel(n: int) -> float:
        k = (n + h / 30.0) % 12.0
        return 255.0 * (lightness - a * max(-1.0, min(k - 3.0, 9.0 - k, 1.0)))

    return channel(0), channel(8), channel(4)


def _parse_colour(value: str) -> tuple[tuple[int, int, int], float] | None:
    """(sRGB triple, alpha) of a CSS colour: keyword, ``#rgb``/``#rgba``/``#rrggbb``/``#rrggbbaa``, ``rgb()``/``rgba()``
    and ``hsl()``/``hsla()`` in the comma or space syntax, with numbers or percentages; None for anything else or a
    colour whose channels are not whole numbers (it cannot match the table exactly)."""
    v = value.strip().lower()
    if v in NAMED_COLOURS:
        return NAMED_COLOURS[v], 1.0
    if v.startswith("#"):
        h = v[1:]
        if len(h) not in (3, 4, 6, 8) or any(c not in "0123456789abcdef" for c in h):
            return None
        pairs = [c * 2 for c in h] if len(h) < 6 else [h[i : i + 2] for i in range(0, len(h), 2)]
        channels = [int(p, 16) for p in pairs]
        return (channels[0], channels[1], channels[2]), (channels[3] / 255.0 if len(channels) == 4 else 1.0)
    m = re.fullmatch(r"(rgba?|hsla?)\(([^()]*)\)", v)
    args = _colour_arguments(m.group(2)) if m else None
    if m is None or args is None:
        return None
    (c1, c2, c3), alpha_text = args
    alpha = _css_number(alpha_text, 1.0)
    if m.group(1).startswith("rgb"):
        rgb = [_css_number(c, 255.0) for c in (c1, c2, c3)]
    else:
        hsl = (_css_number(c1, 360.0, _HUE_UNITS), _css_number(c2, 1.0), _css_number(c3, 1.0))
        rgb = list(_hsl_rgb(*hsl)) if None not in hsl else [None]  # type: ignore[arg-type]
    if alpha is None or None in rgb or any(abs(x - round(x)) > 1e-6 for x in rgb):  # type: ignore[operator, arg-type]
        return None
    r, g, b = (int(round(x)) for x in rgb)  # type: ignore[arg-type]
    return (r, g, b), min(max(alpha, 0.0), 1.0)


def _current_colour(value: str | None, style: dict[str, str]) -> str | None:
    """``value`` with CSS's ``currentColor`` replaced by the ``color`` property in effect (inherited; black where
    none is set), as svgo and icon tools write strokes (``stroke="currentColor"`` in ``<g color="#0000ff">``: the
    valley was skipped as an unknown colour, a designer session)."""
    if value is not None and value.strip().lower() == "currentcolor":
        colour = style.get("color", "black")
        return "black" if colour.strip().lower() in ("currentcolor", "inherit") else colour
    return value


def stroke_role(value: str | None) -> tuple[str, float] | None:
    """(FOLD assignment, alpha) of a stroke value by Origami Simulator's exact colour table, or None if it is not one.

    The alpha of a colour with one (``rgba(255, 0, 0, 0.6)``, ``#ff000099``) is read as ``stroke-opacity`` is: it
    multiplies the fold angle, as a renderer multiplies it into the stroke's opacity."""
    if value is None:
        return None
    v = value.strip().lower()
    if v in LITERAL_ASSIGNMENTS:
        return LITERAL_ASSIGNMENTS[v], 1.0
    colour = _parse_colour(v)
    if colour is None or colour[0] not in ASSIGNMENT_RGB:
        return None
    return ASSIGNMENT_RGB[colour[0]], colour[1]


def stroke_assignment(value: str | None) -> str | None:
    """FOLD assignment for a stroke value by Origami Simulator's exact colour table, or None if it is not one."""
    role = stroke_role(value)
    return role[0] if role is not None else None


def _parse_opacity(value: str | None, what: str, where: str) -> float:
    if value is None or value.strip() == "":
        return 1.0
    v = value.strip()
    try:
        x = float(v[:-1]) / 100.0 if v.endswith("%") else float(v)
    except ValueError:
        raise PatternError(f"{where}: {what} {value!r} is not a number") from None
    if not math.isfinite(x):
        raise PatternError(f"{where}: {what} {value!r} is not finite")
    return min(max(x, 0.0), 1.0)


# ----------------------------------------------------------------------------------------------------- transforms


_TRANSFORM = re.compile(r"\s*(matrix|translate|scale|rotate|skewX|skewY)\s*\(([^)]*)\)\s*,?", re.I)


def _translation(x: float, y: float) -> np.ndarray:
    """The 3×3 matrix that moves by (x, y)."""
    return np.array([[1.0, 0.0, x], [0.0, 1.0, y], [0.0, 0.0, 1.0]])


def parse_transform(value: str, where: str = "transform") -> np.ndarray:
    """3×3 affine matrix of an SVG ``transform`` list (the leftmost transform is applied last)."""
    m = np.eye(3)
    pos = 0
    value = value.strip()
    while pos < len(value):
        match = _TRANSFORM.match(value, pos)
        if not match:
            raise PatternError(f"{where}: cannot read transform {value!r} at {value[pos : pos + 20]!r}")
        name = match.group(1).lower()
        args = [float(x) for x in _NUMBER.findall(match.group(2))]
        if not all(math.isfinite(x) for x in args):
            raise PatternError(f"{where}: a number out of floating-point range in transform {value!r}")
        t = np.eye(3)
        n = len(args)
        if name == "matrix" and n == 6:
            a, b, c, d, e, f = args
            t[:2] = [[a, c, e], [b, d, f]]
        elif name == "translate" and n in (1, 2):
            t[0, 2] = args[0]
            t[1, 2] = args[1] if n == 2 else 0.0
        elif name == "scale" and n in (1, 2):
            t[0, 0] = args[0]
            t[1, 1] = args[1] if n == 2 else args[0]
        elif name == "rotate" and n in (1, 3):
            ang = math.radians(args[0])
            c, s = math.cos(ang), math.sin(ang)
            r = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
            if n == 3:
                cx, cy = args[1], args[2]
                r = _translation(cx, cy) @ r @ _translation(-cx, -cy)
            t = r
        elif name == "skewx" and n == 1:
            t[0, 1] = math.tan(math.radians(args[0]))
        elif name == "skewy" and n == 1:
            t[1, 0] = math.tan(math.radians(args[0]))
        else:
            raise PatternError(f"{where}: {match.group(1)}() with {n} argument(s) in transform {value!r}")
        m = compose(m, t, where, value)
        pos = match.end()
    return m


def compose(outer: np.ndarray, inner: np.ndarray, where: str, value: str) -> np.ndarray:
    """``outer @ inner``, refused with one line naming ``where`` if the product leaves floating-point range (nested
    ``scale(1e300)`` groups): numpy's overflow warnings would otherwise reach the user before a vaguer error."""
    with np.errstate(over="ignore", invalid="ignore"):
        m = outer @ inner
    if not np.all(np.isfinite(m)):
        raise PatternError(f"{where}: transform {value!r} scales the drawing beyond floating-point range")
    return m


# ----------------------------------------------------------------------------------------------------- path data


class _PathScanner:
    """Reads numbers, arc flags and command letters from SVG path data, remembering positions for messages."""

    def __init__(self, d: str, where: str) -> None:
        self.d = d
        self.pos = 0
        self.where = where

    def _skip(self) -> None:
        d, n = self.d, len(self.d)
        while self.pos < n and (d[self.pos] in " \t\r\n\f,"):
            self.pos += 1

    def at_end(self) -> bool:
        self._skip()
        return self.pos >= len(self.d)

    def peek_command(self) -> str | None:
        self._skip()
        if self.pos < len(self.d) and self.d[self.pos].isalpha() and self.d[self.pos] not in "eE":
            return self.d[self.pos]
        return None

    def token(self) -> str:
        self._skip()
        m = re.match(r"\S{1,12}", self.d[self.pos :])
        return m.group(0) if m else "end of data"

    def fail(self, what: str) -> PatternError:
        return PatternError(f"{self.where}: bad path data: {what} at {self.token()!r} (character {self.pos + 1})")

    def number(self) -> float:
        self._skip()
        m = _NUMBER.match(self.d, self.pos)
        if not m:
            raise self.fail("expected a number")
        x = float(m.group(0))
        if not math.isfinite(x):  # named where it starts (it named the token after it; a CLI review session)
            shown = m.group(0) if len(m.group(0)) <= 24 else m.group(0)[:21] + "..."
            raise PatternError(
                f"{self.where}: bad path data: number out of range at {shown!r} (character {self.pos + 1})"
            )
        self.pos = m.end()
        return x

    def flag(self) -> bool:
        self._skip()
        if self.pos < len(self.d) and self.d[self.pos] in "01":
            self.pos += 1
            return self.d[self.pos - 1] == "1"
        raise self.fail("expected an arc flag 0 or 1")

    def has_number(self) -> bool:
        self._skip()
        return bool(_NUMBER.match(self.d, self.pos))


# A raw segment in user units, before the element's transform: ("line", p0, p1), ("cubic", p0, c1, c2, p3),
# ("arc", p0, p1, (cx, cy, rx, ry, phi, theta0, dtheta)).
_Raw = tuple


def _arc_centre(
    p0: np.ndarray, rx: float, ry: float, phi_deg: float, large: bool, sweep: bool, p1: np.ndarray
) -> tuple[float, float, float, float, float, float, float] | None:
    """SVG endpoint → centre parametrisation (SVG 1.1 F.6.5) with radii scaled up when too small (F.6.6).

    Returns ``(cx, cy, rx, ry, phi, theta0, dtheta)`` in radians, or None when the arc is a straight line
    (a zero radius); identical endpoints must be filtered by the caller.
    """
    rx, ry = abs(rx), abs(ry)
    if rx == 0.0 or ry == 0.0:
        return None
    phi = math.radians(phi_deg % 360.0)
    c, s = math.cos(phi), math.sin(phi)
    dx, dy = (p0[0] - p1[0]) / 2.0, (p0[1] - p1[1]) / 2.0
    x1p, y1p = c * dx + s * dy, -s * dx + c * dy
    lam = (x1p / rx) ** 2 + (y1p / ry) ** 2
    if lam > 1.0:
        k = math.sqrt(lam)
        rx, ry = rx * k, ry * k
    num = rx * rx * ry * ry - rx * rx * y1p * y1p - ry * ry * x1p * x1p
    den = rx * rx * y1p * y1p + ry * ry * x1p * x1p
    coef = math.sqrt(max(num, 0.0) / den) if den > 0 else 0.0
    if large == sweep:
        coef = -coef
    cxp, cyp = coef * rx * y1p / ry, -coef * ry * x1p / rx
    cx = c * cxp - s * cyp + (p0[0] + p1[0]) / 2.0
    cy = s * cxp + c * cyp + (p0[1] + p1[1]) / 2.0
    theta0 = math.atan2((y1p - cyp) / ry, (x1p - cxp) / rx)
    theta1 = math.atan2((-y1p - cyp) / ry, (-x1p - cxp) / rx)
    dtheta = theta1 - theta0
    if sweep and dtheta <= 0:
        dtheta += 2 * math.pi
    elif not sweep and dtheta >= 0:
        dtheta -= 2 * math.pi
    return (cx, cy, rx, ry, phi, theta0, dtheta)


def parse_path_data(d: str, where: str, max_segments: int | None = None) -> list[tuple[list[_Raw], bool]]:
    """Sub-paths of SVG path data as (raw segments in user units, closed) pairs.

    Handles every command, absolute and relative, implicit repeats (extra pairs after M are L), smooth control
    point reflection for S/T, and Z returning to the sub-path start. Errors name the offending token. More than
    ``max_segments`` commands (default: the :data:`.limits.PATH_SEGMENTS` limit) raise :class:`PatternError`.
    """
    budget = limits.PATH_SEGMENTS.value if max_segments is None else max_segments
    steps = 0
    sc = _PathScanner(d, where)
    subpaths: list[tuple[list[_Raw], bool]] = []
    segs: list[_Raw] = []
    closed = False
    cur = np.zeros(2)
    start = np.zeros(2)
    last_cubic_ctrl: np.ndarray | None = None
    last_quad_ctrl: np.ndarray | None = None
    cmd: str | None = None
    first = True

    def flush() -> None:
        nonlocal segs, closed
        if segs:
            subpaths.append((segs, closed))
        segs, closed = [], False

    while not sc.at_end():
        steps += 1
        if steps > budget:
            raise PatternError(
                f"{where}: more than {budget:,} path segments (the rest of the file's budget under the limit of "
                f"{limits.PATH_SEGMENTS.value:,}; set the environment variable {limits.PATH_SEGMENTS.variable} "
                "to raise it)"
            )
        letter = sc.peek_command()
        if letter is not None:
            if letter not in "MmLlHhVvCcSsQqTtAaZz":
                raise sc.fail(f"unknown command {letter!r}")
            if first and letter not in "Mm":
                raise sc.fail("path data must start with M or m")
            sc.pos += 1
            cmd = letter
        elif cmd is None or cmd in "Zz":
            raise sc.fail("expected a command letter")
        first = False
        rel = cmd.islower()
        up = cmd.upper()
        base = cur if rel else np.zeros(2)
        if up == "Z":
            if segs and not np.array_equal(cur, start):
                segs.append(("line", cur.copy(), start.copy()))
            if segs:
                closed = True
                flush()
            cur = start.copy()
            last_cubic_ctrl = last_quad_ctrl = None
            continue
        if up == "M":
            flush()
            p = base + (sc.number(), sc.number())
            cur = p
            start = p.copy()
            cmd = "l" if rel else "L"  # implicit repeats are line-tos
            last_cubic_ctrl = last_quad_ctrl = None
            if not sc.has_number():
                continue
            # fall through to read the implicit lineto on the next loop turn
            continue
        if up == "L":
            p = base + (sc.number(), sc.number())
            segs.append(("line", cur.copy(), p))
            cur = p
            last_cubic_ctrl = last_quad_ctrl = None
        elif up == "H":
            x = sc.number() + (cur[0] if rel else 0.0)
            p = np.array([x, cur[1]])
            segs.append(("line", cur.copy(), p))
            cur = p
            last_cubic_ctrl = last_quad_ctrl = None
        elif up == "V":
            y = sc.number() + (cur[1] if rel else 0.0)
            p = np.array([cur[0], y])
            segs.append(("line", cur.copy(), p))
            cur = p
            last_cubic_ctrl = last_quad_ctrl = None
        elif up == "C":
            c1 = base + (sc.number(), sc.number())
            c2 = base + (sc.number(), sc.number())
            p = base + (sc.number(), sc.number())
            segs.append(("cubic", cur.copy(), c1, c2, p))
            cur, last_cubic_ctrl, last_quad_ctrl = p, c2, None
        elif up == "S":
            c1 = 2 * cur - last_cubic_ctrl if last_cubic_ctrl is not None else cur.copy()
            c2 = base + (sc.number(), sc.number())
            p = base + (sc.number(), sc.number())
            segs.append(("cubic", cur.copy(), c1, c2, p))
            cur, last_cubic_ctrl, last_quad_ctrl = p, c2, None
        elif up == "Q":
            q = base + (sc.number(), sc.number())
            p = base + (sc.number(), sc.number())
            segs.append(("cubic", cur.copy(), cur + 2.0 / 3.0 * (q - cur), p + 2.0 / 3.0 * (q - p), p))
            cur, last_quad_ctrl, last_cubic_ctrl = p, q, None
        elif up == "T":
            q = 2 * cur - last_quad_ctrl if last_quad_ctrl is not None else cur.copy()
            p = base + (sc.number(), sc.number())
            segs.append(("cubic", cur.copy(), cur + 2.0 / 3.0 * (q - cur), p + 2.0 / 3.0 * (q - p), p))
            cur, last_quad_ctrl, last_cubic_ctrl = p, q, None
        elif up == "A":
            rx, ry, rot = sc.number(), sc.number(), sc.number()
            large, sweep = sc.flag(), sc.flag()
            p = base + (sc.number(), sc.number())
            if not np.array_equal(p, cur):
                with np.errstate(over="ignore", invalid="ignore"):  # huge radii: refused downstream, with the element
                    arc = _arc_centre(cur, rx, ry, rot, large, sweep, p)
                if arc is None:
                    segs.append(("line", cur.copy(), p))
                else:
                    segs.append(("arc", cur.copy(), p, arc))
            cur = p
            last_cubic_ctrl = last_quad_ctrl = None
    flush()
    return subpaths


# ----------------------------------------------------------------------------------------------------- geometry


def _transform_points(m: np.ndarray, pts: np.ndarray) -> np.ndarray:
    pts = np.asarray(pts, dtype=float).reshape(-1, 2)
    with np.errstate(over="ignore", invalid="ignore"):  # out-of-range points are refused, with their element, later
        return pts @ m[:2, :2].T + m[:2, 2]


def _transform_arc(
    m: np.ndarray, arc: tuple[float, float, float, float, float, float, float]
) -> tuple[float, float, float, float, float, float, float]:
    """Exact affine image of the elliptical arc ``c + R(phi)·diag(rx, ry)·(cos t, sin t)``, t in the sweep.

    The linear part ``A·R(phi)·diag(rx, ry)`` is decomposed by SVD into ``R(phi')·diag(s1, ±s2)·R(-psi)``; the
    image is the ellipse with radii ``s1, |s2|`` rotated by ``phi'``, its angles shifted by ``-psi`` (and mirrored
    when the transform flips orientation, which also reverses the sweep).
    """
    cx, cy, rx, ry, phi, theta0, dtheta = arc
    a = m[:2, :2]
    cphi, sphi = math.cos(phi), math.sin(phi)
    with np.errstate(over="ignore", invalid="ignore"):
        lin = a @ np.array([[cphi, -sphi], [sphi, cphi]]) @ np.diag([rx, ry])
    centre = _transform_points(m, np.array([cx, cy]))[0]
    if not np.all(np.isfinite(lin)):  # radii beyond floating-point range: refused, with the element, downstream
        return (float(centre[0]), float(centre[1]), math.inf, math.inf, 0.0, theta0, dtheta)
    u, s, vt = np.linalg.svd(lin)
    s = s.astype(float).copy()
    if np.linalg.det(u) < 0:
        u[:, 1] *= -1
        s[1] = -s[1]
    if np.linalg.det(vt) < 0:
        vt[1, :] *= -1
        s[1] = -s[1]
    psi = math.atan2(vt[0, 1], vt[0, 0])
    new_phi = math.atan2(u[1, 0], u[0, 0])
    t0, dt = theta0 - psi, dtheta
    if s[1] < 0:
        t0, dt = -t0, -dt
    return (float(centre[0]), float(centre[1]), float(s[0]), float(abs(s[1])), new_phi, t0, dt)


def _to_segment(raw: _Raw, m: np.ndarray) -> CurveSegment:
    kind = raw[0]
    if kind == "line":
        return CurveSegment("line", _transform_points(m, np.array([raw[1], raw[2]])))
    if kind == "cubic":
        return CurveSegment("cubic", _transform_points(m, np.array(raw[1:5])))
    ends = _transform_points(m, np.array([raw[1], raw[2]]))
    return CurveSegment("arc", ends, _transform_arc(m, raw[3]))


USER_UNITS = {unit: mm / PX_MM for unit, mm in UNIT_MM.items()}
"""User units per unit of an absolute length on a shape's attribute: a user unit is a CSS px (1/96 in) whatever
the viewBox does after (SVG 1.1 §7.10), as :func:`_viewport` takes it for a root without a viewBox."""

RELATIVE_UNITS = ("em", "ex", "ch", "rem", "vw", "vh", "vmin", "vmax")
"""CSS units relative to a font or a browser window: nothing in a crease pattern gives their size."""

_AXIS = {
    "x": 0,
    "x1": 0,
    "x2": 0,
    "cx": 0,
    "width": 0,
    "rx": 0,
    "y": 1,
    "y1": 1,
    "y2": 1,
    "cy": 1,
    "height": 1,
    "ry": 1,
}
"""Which viewport side a percentage of each attribute is of (SVG 1.1 §7.10); others (``r``) take the diagonal."""


def _unit_scale(elem: _Element, matrix: np.ndarray) -> float | None:
    """How many times the size they say an element's lengths in physical units (mm, cm, in, pt, pc, Q) are drawn,
    when that is not 1: they are CSS lengths of 96 px to the inch, and a viewBox or a transform may make a user
    unit other than a px (``x1="50mm"`` in a 100 mm sheet with ``viewBox="0 0 100 100"`` lands 189 mm down)."""
    units = [m.group(2).lower() for n in (*_AXIS, "r") if (m := _QUANTITY.fullmatch(elem.attrib.get(n, "").strip()))]
    if not any(u in USER_UNITS and u not in ("", "px") for u in units):
        return None
    with np.errstate(over="ignore", invalid="ignore"):
        ratio = math.sqrt(abs(float(np.linalg.det(matrix[:2, :2])))) / PX_MM
    return ratio if math.isfinite(ratio) and abs(ratio - 1.0) > 0.01 else None


def _percent_of(box: tuple[float, float] | None, name: str, where: str, shown: str) -> float:
    """What 100 % of attribute ``name`` is in a viewport of ``box`` (width, height in user units)."""
    if box is None:
        raise PatternError(
            f"{where}: attribute {name}={shown!r} is a percentage of the viewport, whose size the file does not give "
            "(give the <svg> a viewBox, or a width and height)"
        )
    axis = _AXIS.get(name)
    return box[axis] if axis is not None else math.hypot(*box) / math.sqrt(2.0)


def _attr_float(
    elem: _Element, name: str, where: str, default: float | None = 0.0, box: tuple[float, float] | None = None
) -> float:
    """Attribute ``name`` as a length in user units: a number, an absolute length (px, mm, cm, in, pt, pc, Q) or a
    percentage of the viewport ``box`` (None: the file gives no size); ``default`` when it is absent."""
    value = elem.attrib.get(name)
    if value is None or value.strip() == "":
        if default is None:
            raise PatternError(f"{where}: missing attribute {name}")
        return default
    shown = value if len(value) <= 40 else value[:37] + "..."
    m = _QUANTITY.fullmatch(value.strip())
    unit = m.group(2).lower() if m else ""
    if m and unit in USER_UNITS:
        return float(m.group(1)) * USER_UNITS[unit]
    if m and unit == "%":
        return float(m.group(1)) / 100.0 * _percent_of(box, name, where, shown)
    if m and unit in RELATIVE_UNITS:
        raise PatternError(
            f"{where}: attribute {name}={shown!r} is in {unit}, a unit relative to a font or window that a crease "
            "pattern does not give: use user units or px, mm, cm, in, pt, pc, Q"
        )
    raise PatternError(
        f"{where}: attribute {name}={shown!r} is not a number (a length in user units, or with px, mm, cm, in, pt, "
        "pc, Q or %)"
    )


def _points_attr(elem: _Element, where: str) -> np.ndarray:
    text = elem.attrib.get("points", "")
    nums = _NUMBER.findall(text)
    stripped = _NUMBER.sub(" ", text).replace(",", " ").strip()
    if stripped:
        raise PatternError(f"{where}: bad points attribute near {stripped.split()[0]!r}")
    if len(nums) % 2:
        raise PatternError(f"{where}: points attribute has an odd number of coordinates ({len(nums)})")
    return np.array([float(x) for x in nums]).reshape(-1, 2)


def _ellipse_arcs(cx: float, cy: float, rx: float, ry: float) -> list[_Raw]:
    """A full ellipse as two half arcs (start ≠ end on each, so no segment is degenerate)."""
    p0, p1 = np.array([cx + rx, cy]), np.array([cx - rx, cy])
    return [
        ("arc", p0, p1, (cx, cy, rx, ry, 0.0, 0.0, math.pi)),
        ("arc", p1, p0.copy(), (cx, cy, rx, ry, 0.0, math.pi, math.pi)),
    ]


def _shape_subpaths(
    elem: _Element, where: str, budget: int | None = None, box: tuple[float, float] | None = None
) -> list[tuple[list[_Raw], bool]]:
    """Raw sub-paths (user units) of one shape element (a path of more than ``budget`` commands raises; ``box``:
    the viewport's size in user units, for percentages)."""
    tag = elem.tag

    def attr(name: str) -> float:
        return _attr_float(elem, name, where, box=box)

    if tag == "path":
        return parse_path_data(elem.attrib.get("d", ""), where, budget)
    if tag == "line":
        p0 = np.array([attr("x1"), attr("y1")])
        p1 = np.array([attr("x2"), attr("y2")])
        return [([("line", p0, p1)], False)]
    if tag in ("polyline", "polygon"):
        pts = _points_attr(elem, where)
        if budget is not None and len(pts) > budget:
            limits.PATH_SEGMENTS.check(limits.PATH_SEGMENTS.value + len(pts) - budget, where)
        segs: list[_Raw] = [("line", pts[i], pts[i + 1]) for i in range(len(pts) - 1)]
        closed = tag == "polygon" and len(pts) > 2
        if closed and not np.array_equal(pts[-1], pts[0]):
            segs.append(("line", pts[-1], pts[0]))
        return [(segs, closed)] if segs else []
    if tag == "rect":
        x, y = attr("x"), attr("y")
        w, h = attr("width"), attr("height")
        if w <= 0 or h <= 0:
            return []
        rx_s, ry_s = elem.attrib.get("rx"), elem.attrib.get("ry")
        rx = attr("rx") if rx_s not in (None, "", "auto") else None
        ry = attr("ry") if ry_s not in (None, "", "auto") else None
        if rx is None and ry is None:
            rx = ry = 0.0
        elif rx is None:
            rx = ry
        elif ry is None:
            ry = rx
        rx, ry = min(max(rx, 0.0), w / 2), min(max(ry, 0.0), h / 2)
        if rx == 0.0 or ry == 0.0:
            c = np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h]])
            return [([("line", c[i], c[(i + 1) % 4]) for i in range(4)], True)]
        hp = math.pi / 2
        pts = {
            "t0": np.array([x + rx, y]),
            "t1": np.array([x + w - rx, y]),
            "r0": np.array([x + w, y + ry]),
            "r1": np.array([x + w, y + h - ry]),
            "b0": np.array([x + w - rx, y + h]),
            "b1": np.array([x + rx, y + h]),
            "l0": np.array([x, y + h - ry]),
            "l1": np.array([x, y + ry]),
        }
        segs = []

        def edge(a: str, b: str) -> None:
            if not np.array_equal(pts[a], pts[b]):
                segs.append(("line", pts[a], pts[b]))

        edge("t0", "t1")
        segs.append(("arc", pts["t1"], pts["r0"], (x + w - rx, y + ry, rx, ry, 0.0, -hp, hp)))
        edge("r0", "r1")
        segs.append(("arc", pts["r1"], pts["b0"], (x + w - rx, y + h - ry, rx, ry, 0.0, 0.0, hp)))
        edge("b0", "b1")
        segs.append(("arc", pts["b1"], pts["l0"], (x + rx, y + h - ry, rx, ry, 0.0, hp, hp)))
        edge("l0", "l1")
        segs.append(("arc", pts["l1"], pts["t0"], (x + rx, y + ry, rx, ry, 0.0, math.pi, hp)))
        return [(segs, True)]
    if tag == "circle":
        r = attr("r")
        if r <= 0:
            return []
        return [(_ellipse_arcs(attr("cx"), attr("cy"), r, r), True)]
    if tag == "ellipse":
        rx, ry = attr("rx"), attr("ry")
        if rx <= 0 or ry <= 0:
            return []
        return [(_ellipse_arcs(attr("cx"), attr("cy"), rx, ry), True)]
    return []


# ----------------------------------------------------------------------------------------------------- viewport


def _length_mm(value: str | None, name: str = "width", where: str = "SVG <svg>") -> tuple[float | None, bool]:
    """(millimetres, has a physical unit) for the root's width/height ``name``; (None, False) if absent, ``auto`` or
    a percentage (the viewBox then gives the size). Anything else that is not an SVG length is refused: a size in
    metres (``0.15m``, not an SVG unit), in ``em`` or with a typo was read as no size at all and the sheet folded at
    the viewBox's pixel size (39.7 mm instead of 150 mm, no word; a designer session), where the same unit on a
    shape is refused."""
    if value is None or value.strip().lower() in ("", "auto"):
        return None, False
    m = _QUANTITY.fullmatch(value.strip())
    unit = m.group(2).lower() if m else ""
    if m and unit == "%":
        return None, False
    if m and unit in UNIT_MM:
        return float(m.group(1)) * UNIT_MM[unit], unit not in ("", "px")
    shown = value if len(value) <= 40 else value[:37] + "..."
    hint = f" ({unit} is not an SVG unit: write it in mm)" if m and unit in ("m", "km", "um", "µm", "nm") else ""
    raise PatternError(
        f"{where}: <svg> {name}={shown!r} is not a length the sheet's size can be read from: give a number with "
        f"px, mm, cm, in, pt, pc or Q (or leave it out and let the viewBox give the size){hint}"
    )


def _viewbox(elem: _Element, where: str) -> tuple[float, float, float, float] | None:
    """An element's ``viewBox`` (x, y, width, height), None without one; refused unless the size is positive."""
    vb = elem.attrib.get("viewBox")
    if vb is None or not vb.strip():
        return None
    nums = [float(x) for x in _NUMBER.findall(vb)]
    if len(nums) != 4 or not (nums[2] > 0 and nums[3] > 0) or not all(map(math.isfinite, nums)):
        raise PatternError(f"{where}: viewBox {vb!r} must be four numbers with positive width and height")
    return nums[0], nums[1], nums[2], nums[3]


def _fit(vbox: tuple[float, float, float, float], par: str | None, width: float, height: float) -> np.ndarray:
    """3×3 matrix that fits the user box ``vbox`` into a ``width × height`` viewport at the origin, following
    ``preserveAspectRatio`` ``par`` (SVG 1.1 §7.8; default ``xMidYMid meet``, ``none`` scales each axis on its own)."""
    vx, vy, vw, vh = vbox
    sx, sy = width / vw, height / vh
    words = (par or "").split()
    if words[:1] == ["defer"]:  # only meaningful on <image>
        words = words[1:]
    align = words[0] if words else "xMidYMid"
    tx = ty = 0.0
    if align != "none":
        s = max(sx, sy) if words[1:2] == ["slice"] else min(sx, sy)
        fx = {"xMin": 0.0, "xMid": 0.5, "xMax": 1.0}.get(align[:4], 0.5)
        fy = {"YMin": 0.0, "YMid": 0.5, "YMax": 1.0}.get(align[4:], 0.5)
        tx, ty = fx * (width - vw * s), fy * (height - vh * s)
        sx = sy = s
    return np.array([[sx, 0.0, tx - vx * sx], [0.0, sy, ty - vy * sy], [0.0, 0.0, 1.0]])


def _nested_viewport(
    elem: _Element, use: _Element | None, box: tuple[float, float] | None, where: str
) -> tuple[np.ndarray, tuple[float, float] | None] | None:
    """The viewport of a nested ``<svg>`` or of a ``<symbol>`` (or ``<svg>``) drawn by ``use`` (SVG 1.1 §7.9, §5.6):
    the matrix from its user units to its parent's, and its viewport's size in its own user units (None: unknown).

    ``x``/``y`` place it; ``width``/``height`` (the use's, where it gives them; default 100 % of the parent's
    viewport ``box``) size it; its ``viewBox`` is fitted in as the root's is (:func:`_fit`). None when the viewport
    is empty (a width or height of 0 draws nothing). Clipping to the viewport is not done."""
    sizes: list[float | None] = []
    for name in ("width", "height"):
        source = use if use is not None and use.attrib.get(name, "").strip() not in ("", "auto") else elem
        if source.attrib.get(name, "").strip() in ("", "auto"):
            sizes.append(None if box is None else box[_AXIS[name]])
        else:
            sizes.append(_attr_float(source, name, where if source is elem else _describe(source), box=box))
    width, height = sizes
    if (width is not None and width <= 0) or (height is not None and height <= 0):
        return None
    x, y = _attr_float(elem, "x", where, box=box), _attr_float(elem, "y", where, box=box)
    shift = _translation(x, y)
    vbox = _viewbox(elem, where)
    if vbox is None:
        return shift, (width, height) if width is not None and height is not None else None
    if width is None or height is None:
        raise PatternError(
            f"{where}: its viewBox needs the size of its viewport, which the file does not give: give it (or the <use> "
            "that draws it) a width and height"
        )
    return shift @ _fit(vbox, elem.attrib.get("preserveAspectRatio"), width, height), (vbox[2], vbox[3])


def _viewport(root: _Element, where: str) -> tuple[np.ndarray, float, float, tuple[float, float] | None]:
    """User units → mm (y up) as a 3×3 matrix, the viewport's width and height in mm, and its size in user units
    (what percentages are of; None when the file gives no size). A width or height that is not a finite length is
    refused here (``width="1e400mm"`` was read as infinity, made every coordinate nan, and the error blamed the first
    shape; a CLI review session); a finite absurd one is caught at the coordinates, with a hint at the units.

    With a ``viewBox`` the user box is fitted into ``width × height`` (:func:`_fit`). Missing ``width``/``height``
    fall back to the viewBox size in px. Without one, a user unit is a px. The result ends with the flip
    (x, y) → (x, −y).
    """
    w_mm, _ = _length_mm(root.attrib.get("width"), "width", where)
    h_mm, _ = _length_mm(root.attrib.get("height"), "height", where)
    for name, value in (("width", w_mm), ("height", h_mm)):
        if value is not None and not math.isfinite(value):  # 1e400mm: inf, then nan coordinates
            raise PatternError(f"{where}: {name}={root.attrib.get(name)!r} is not a finite length")
    vbox = _viewbox(root, where)
    if vbox is not None:
        vw, vh = vbox[2], vbox[3]
        if w_mm is None and h_mm is None:
            w_mm, h_mm = vw * PX_MM, vh * PX_MM
        elif w_mm is None:
            w_mm = h_mm * vw / vh
        elif h_mm is None:
            h_mm = w_mm * vh / vw
        m = _fit(vbox, root.attrib.get("preserveAspectRatio"), w_mm, h_mm)
        box: tuple[float, float] | None = (vw, vh)
    else:
        m = np.diag([PX_MM, PX_MM, 1.0])
        box = (w_mm / PX_MM, h_mm / PX_MM) if w_mm is not None and h_mm is not None else None
    flip = np.diag([1.0, -1.0, 1.0])
    return flip @ m, float(w_mm or 0.0), float(h_mm or 0.0), box


# ----------------------------------------------------------------------------------------------------- reading


def _href(use: _Element) -> str:
    """The id a ``<use>`` names (``href`` or ``xlink:href`` = ``#id``), or "" when it names none in this file."""
    ref = use.attrib.get("href") or use.attrib.get("http://www.w3.org/1999/xlink}href") or ""
    return ref.strip()[1:] if ref.strip().startswith("#") else ""


def _self_and_ancestors(elem: _Element, parents: dict[int, _Element]) -> list[_Element]:
    """``elem`` and its ancestors in the document (at most limits.NESTING of them)."""
    out = [elem]
    while id(out[-1]) in parents:
        out.append(parents[id(out[-1])])
    return out


def _lines(lines: list[int]) -> str:
    """``line 7`` or ``lines 7, 8, … and 2 more`` (each line once, at most eight listed)."""
    lines = list(dict.fromkeys(lines))
    return ("line " if len(lines) == 1 else "lines ") + _names([str(x) for x in lines], limit=8)


def _no_stroke(stroke: str | None) -> bool:
    """Whether a shape draws no line: no ``stroke`` (SVG's default is none), ``none`` or ``transparent``."""
    return stroke is None or stroke.strip().lower() in ("none", "transparent", "")


def _fold_angle(assignment: str, opacity: float) -> float | None:
    """A stroke's fold angle from its total opacity (``opacity × stroke-opacity × alpha``): ∓180° × opacity for a
    mountain/valley (None, "no angle given", at 0, so ``--angle`` can fill it), 0° for a facet, None otherwise."""
    if assignment in ("M", "V") and opacity != 0.0:
        return (-180.0 if assignment == "M" else 180.0) * opacity
    return 0.0 if assignment == "F" else None


def _invisible(style: dict[str, str]) -> bool:
    """Whether a shape's inherited ``visibility`` hides it (``hidden``/``collapse``; a child may say ``visible``).

    Unlike ``display:none`` the property is inherited and only hides the shapes themselves, so it is read where a
    shape is drawn, not where a group starts: that is what lets a visible child show through a hidden group."""
    return style.get("visibility", "").strip().lower() in ("hidden", "collapse")


def _names(items: list[str], limit: int = 4, sep: str = ", ") -> str:
    """The first ``limit`` of ``items`` joined, and how many more there are."""
    return sep.join(items[:limit]) + (f" and {len(items) - limit} more" if len(items) > limit else "")


def _group_opacity(own: dict[str, str]) -> float | None:
    """A container's own ``opacity`` when it is below 1, else None (unreadable values too: it is never used)."""
    try:
        opacity = _parse_opacity(own.get("opacity"), "opacity", "")
    except PatternError:
        return None
    return opacity if opacity < 1.0 else None


ID_SHOWN = 40
"""Most characters of an element's id a message quotes (a 1 MB id made a 1 MB message line)."""


def _describe(elem: _Element) -> str:
    ident = elem.attrib.get("id")
    if ident:
        # one line whatever the id holds (an id with &#10; made a four-line error), and a short one
        ident = "".join(c if c.isprintable() else repr(c)[1:-1] for c in ident)
        ident = ident if len(ident) <= ID_SHOWN else ident[: ID_SHOWN - 3] + "..."
    tag = f"<{elem.tag} id='{ident}'>" if ident else f"<{elem.tag}>"
    return f"SVG {tag} (line {elem.line})"


@dataclass(frozen=True)
class _Place:
    """How an element is drawn: its user units → mm (y up) matrix, the properties it inherits, the ``<use>``
    elements it is drawn through, innermost last (none for the element in its own place), the groups around it
    with an opacity of their own (not a fold angle: :meth:`_Reader.warnings` says so) and the size of its viewport
    (for percentages)."""

    matrix: np.ndarray
    style: dict[str, str]
    via: tuple[_Element, ...] = ()
    faded: tuple[str, ...] = ()  # the groups around it whose own opacity is below 1 (their descriptions)
    box: tuple[float, float] | None = None  # its viewport's width and height in its user units (None: not given)


class _Reader:
    """One document's walk: every visible shape with a role colour becomes crease curves; what is skipped is kept
    for one warning a kind (:meth:`warnings`). The tree is walked with an explicit stack (``todo``), not recursion."""

    def __init__(self, root: _Element, source_name: str, warnings: list[str]) -> None:
        self.root, self.source_name = root, source_name
        self.rules: list[_Rule] = []
        self.ids: dict[str, _Element] = {}  # the targets of <use> (the first element of each id, as browsers take it)
        self.parents: dict[int, _Element] = {}  # id(element) → its parent, to refuse a <use> inside what it names
        self._index(warnings)
        self.curves: list[CreaseCurve] = []
        self.unknown: dict[str, list[int]] = {}  # stroke as written → lines
        self.filled: list[str] = []  # shapes without a stroke, filled in a role colour: perhaps meant as the sheet
        self.unresolved: list[int] = []  # lines of <use> elements whose href names no element
        self.cycles: list[int] = []  # lines of <use> elements that would draw themselves again
        self.rescaled: list[str] = []  # shapes whose lengths in mm, in, ... are drawn at another size than they say
        self.flat: list[str] = []  # mountains and valleys whose opacity gives 0°
        self.group_opacity: dict[str, list[float]] = {}  # group → [its opacity, creases in it]
        self.segment_budget = limits.PATH_SEGMENTS.value
        self.visits_left = limits.SVG_ELEMENTS.value  # elements drawn, clones included: nested <use> cannot multiply
        self.todo: list[tuple[_Element, _Place]] = []

    def _index(self, warnings: list[str]) -> None:
        """Ids, parents and ``<style>`` rules of the whole document, in document order."""
        pending = [self.root]  # explicit stack (nesting depth is bounded by limits.NESTING anyway)
        while pending:
            elem = pending.pop()
            if "id" in elem.attrib:
                self.ids.setdefault(elem.attrib["id"], elem)
            for child in elem.children:
                self.parents[id(child)] = elem
            if elem.tag == "style":
                where = f"{self.source_name} <style> (line {elem.line})"
                self.rules.extend(_parse_stylesheet(elem.text, warnings, where))
            pending.extend(reversed(elem.children))
        for i, r in enumerate(self.rules):
            r.order = i

    def read_steps(self, place: _Place) -> Generator[str, None, None]:
        """Draw the document from its root, placed by ``place``, in units of :data:`VISITS_PER_UNIT` elements (a
        Blender import runs them in a job's slices)."""
        self.todo.append((self.root, place))
        visits = 0
        while self.todo:
            self.visit(*self.todo.pop())
            visits += 1
            if visits % VISITS_PER_UNIT == 0:
                yield "svg elements"

    def visit(self, elem: _Element, place: _Place) -> None:
        """Read one element; its children (or the element a ``<use>`` names) go on ``todo``."""
        via = place.via
        used = bool(via) and elem is self.ids.get(_href(via[-1]))  # the target of a <use>: a <symbol> is drawn there
        if elem.tag.startswith("#foreign:") or (elem.tag in SKIPPED_CONTAINERS and not (used and elem.tag == "symbol")):
            return
        self.visits_left -= 1
        if self.visits_left < 0:
            limits.SVG_ELEMENTS.check(
                limits.SVG_ELEMENTS.value - self.visits_left, f"{self.source_name} (<use> copies included)"
            )
        where = _describe(elem) + "".join(f" via <use> (line {u.line})" for u in reversed(via))
        own = _own_style(elem, self.rules)
        style = dict(place.style)
        for key in INHERITED:
            if key in own and own[key].lower() != "inherit":
                style[key] = own[key]
        if own.get("display", "").lower() == "none":
            return
        matrix = place.matrix
        if "transform" in elem.attrib:
            value = elem.attrib["transform"]
            matrix = compose(matrix, parse_transform(value, where), where, value)
        faded, box = place.faded, place.box
        if elem.tag not in SHAPES and (opacity := _group_opacity(own)) is not None:
            self.group_opacity[where] = [opacity, 0]
            faded = (*faded, where)
        if elem.tag in ("svg", "symbol") and elem is not self.root:  # a viewport of its own
            nested = _nested_viewport(elem, via[-1] if used else None, box, where)
            if nested is None:
                return
            matrix, box = compose(matrix, nested[0], where, "its viewport"), nested[1]
        place = _Place(matrix, style, via, faded, box)
        if elem.tag == "use":
            self._use(elem, place, where)
        elif elem.tag in SHAPES:
            self._shape(elem, place, own, where)
        else:
            self.todo.extend((child, place) for child in reversed(elem.children))

    def _use(self, elem: _Element, place: _Place, where: str) -> None:
        """A clone (Inkscape's Edit ▸ Clone): the element it names, moved by x, y, unless it names nothing or would
        draw itself again."""
        target = self.ids.get(_href(elem))
        if target is None:
            self.unresolved.append(elem.line)
        elif any(target is a for u in (elem, *place.via) for a in _self_and_ancestors(u, self.parents)):
            self.cycles.append(elem.line)
        else:
            x, y = _attr_float(elem, "x", where, box=place.box), _attr_float(elem, "y", where, box=place.box)
            matrix = compose(place.matrix, _translation(x, y), where, f"x={x:g} y={y:g}")
            self.todo.append((target, _Place(matrix, place.style, (*place.via, elem), place.faded, place.box)))

    def _shape(self, elem: _Element, place: _Place, own: dict[str, str], where: str) -> None:
        """A visible shape: crease curves if its stroke has a role colour, else noted for a warning."""
        style = place.style
        if _invisible(style):
            return
        stroke = _current_colour(style.get("stroke"), style)
        role = stroke_role(stroke)
        subpaths = _shape_subpaths(elem, where, self.segment_budget, place.box)
        ratio = _unit_scale(elem, place.matrix)
        if ratio is not None:
            self.rescaled.append(f"{where} (drawn {ratio:.3g}× the size written)")
        self.segment_budget -= sum(len(segs) for segs, _ in subpaths)
        if self.segment_budget < 0:
            limits.PATH_SEGMENTS.check(
                limits.PATH_SEGMENTS.value - self.segment_budget, f"{self.source_name} ({where})"
            )
        if not subpaths:
            return
        if _no_stroke(stroke):  # not drawn as a line, so not a crease (LibreOffice's bounding boxes)
            if elem.tag != "line" and stroke_role(_current_colour(style.get("fill", "black"), style)) is not None:
                self.filled.append(where)
            return
        if role is None:
            self.unknown.setdefault((stroke or "").strip(), []).append(elem.line)  # as written
            return
        assignment, alpha = role
        opacity = _parse_opacity(own.get("opacity"), "opacity", where)
        stroke_opacity = _parse_opacity(style.get("stroke-opacity"), "stroke-opacity", where)
        angle = _fold_angle(assignment, opacity * stroke_opacity * alpha)
        if assignment in ("M", "V"):
            for group in place.faded:
                self.group_opacity[group][1] += 1
            if angle is None:
                self.flat.append(where)
        sampled = elem.attrib.get(SAMPLED_ATTRIBUTE, "").strip() == SAMPLED_VALUE
        for k, (raw_segs, closed) in enumerate(subpaths):
            source = where if len(subpaths) == 1 else f"{where} subpath {k + 1}"
            segments = [_to_segment(r, place.matrix) for r in raw_segs]
            self.curves.append(CreaseCurve(segments, assignment, angle, closed=closed, source=source, sampled=sampled))

    def warnings(self) -> list[str]:
        """One line for each kind of element skipped."""
        out: list[str] = []
        name = self.source_name
        if self.unknown:
            parts = []
            for colour, lines in self.unknown.items():
                shown = ", ".join(str(x) for x in lines[:8]) + (", ..." if len(lines) > 8 else "")
                noun = "element" if len(lines) == 1 else "elements"
                label = "lines" if len(lines) > 1 else "line"
                parts.append(f"{colour} ({len(lines)} {noun}: {label} {shown})")
            out.append(f"{name}: unknown stroke colours (elements skipped): " + ", ".join(parts))
        if self.filled:
            out.append(
                f"{name}: {len(self.filled)} filled shape(s) without a stroke skipped (only strokes are read; to make "
                f"one the sheet's outline, give it a black stroke): {_names(self.filled)}"
            )
        if self.rescaled:
            out.append(
                f"{name}: lengths with units on shapes are CSS lengths (96 px, that is 96 user units, to the inch), "
                f"which this file's viewBox or transforms draw at another size, as browsers do: {_names(self.rescaled)}"
                "; write them without units to mean the file's own units"
            )
        if self.flat:
            out.append(
                f"{name}: {len(self.flat)} crease(s) with opacity 0 fold by 0° and stay flat: {_names(self.flat)}; "
                f"{ANGLE_HINT}, or give creases without an angle one with --angle (command line)"
            )
        held = [f"{g} has opacity {o:g} around {int(n)} crease(s)" for g, (o, n) in self.group_opacity.items() if n]
        if held:
            out.append(
                f"{name}: a group's opacity is not read as a fold angle: {_names(held, sep='; ')}; its creases fold "
                f"by their own strokes' opacity (180° when full): {ANGLE_HINT} on each stroke"
            )
        if self.unresolved:
            out.append(
                f"{name}: <use> elements that name no element of the file are skipped ({_lines(self.unresolved)})"
            )
        if self.cycles:
            out.append(f"{name}: <use> elements that would draw themselves again are skipped ({_lines(self.cycles)})")
        return out


def parse_svg_text(text: str | bytes, source_name: str = "<svg>") -> SvgDrawing:
    """Read an SVG document given as text; see the module docstring. ``source_name`` prefixes file-level errors."""
    return run_to_end(parse_svg_steps(text, source_name))


def parse_svg_steps(text: str | bytes, source_name: str = "<svg>") -> Generator[str, None, SvgDrawing]:
    """:func:`parse_svg_text` in units of work: the XML, the document's index, then its elements in units of
    :data:`VISITS_PER_UNIT`."""
    root = _parse_xml(text, source_name)
    if root.tag != "svg":
        raise PatternError(f"{source_name}: not an SVG file (root element is <{root.tag}>, line {root.line})")
    yield "xml"
    warnings: list[str] = []
    reader = _Reader(root, source_name, warnings)
    viewport, width_mm, height_mm, box = _viewport(root, source_name)
    yield "svg index"
    yield from reader.read_steps(_Place(viewport, {}, box=box))
    warnings += reader.warnings()
    if not reader.curves:
        raise PatternError(
            f"{source_name}: no usable crease element (path/line/polyline/polygon/rect/circle/ellipse with a stroke "
            "colour from Origami Simulator's table: black border, red mountain, blue valley, green cut, yellow facet, "
            "magenta undriven)"
        )
    return SvgDrawing(reader.curves, warnings, width_mm, height_mm, source_name)


def read_svg(path: str | Path) -> SvgDrawing:
    """Read an SVG file in Origami Simulator's convention into crease curves (mm, y up). See :func:`parse_svg_text`."""
    return run_to_end(read_svg_steps(path))


def read_svg_steps(path: str | Path) -> Generator[str, None, SvgDrawing]:
    """:func:`read_svg` in units of work (:func:`parse_svg_steps`)."""
    from .reader import read_input_bytes

    p = Path(path)
    return (yield from parse_svg_steps(read_input_bytes(p, "SVG"), p.name))
