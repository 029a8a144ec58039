"""Generate the project's example crease patterns (``examples/*.svg``) in Origami Simulator's SVG convention.

Each file is a 150 mm sheet (``width="150mm"`` + ``viewBox="0 0 150 150"``, so one user unit is one millimetre;
SVG y points down). Black is the border, red mountain, blue valley; stroke opacity × 180° is the fold angle
(0.6 → 108°, the paper's angle). Every crease starts and ends exactly on the border (at a border vertex or on a
border line), so discretisation needs no trimming.

Run ``python examples/make_examples.py`` from the repository root to rewrite them.
"""

from __future__ import annotations

import math
from pathlib import Path

HERE = Path(__file__).resolve().parent
SIZE = 150.0
BORDER = "#000000"
MOUNTAIN = "#ff0000"
VALLEY = "#0000ff"


def _svg(title: str, body: list[str]) -> str:
    lines = [
        '<?xml version="1.0" encoding="utf-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{SIZE:g}mm" height="{SIZE:g}mm" '
        f'viewBox="0 0 {SIZE:g} {SIZE:g}">',
        f"  <title>{title}</title>",
        *("  " + b for b in body),
        "</svg>",
        "",
    ]
    return "\n".join(lines)


def _path(d: str, stroke: str, opacity: float | None = None, ident: str | None = None) -> str:
    op = f' opacity="{opacity:g}"' if opacity is not None else ""
    i = f' id="{ident}"' if ident else ""
    return f'<path{i} d="{d}" fill="none" stroke="{stroke}" stroke-width="0.5"{op}/>'


def square_border() -> str:
    return f'<rect id="border" x="0" y="0" width="{SIZE:g}" height="{SIZE:g}" fill="none" stroke="{BORDER}"/>'


def single_curve() -> str:
    """One curved valley crease across a square (paper Fig. 1), folded 108°."""
    crease = _path("M 55 0 C 95 45 95 105 55 150", VALLEY, 0.6, "valley")
    return _svg("single curved valley crease, 108 degrees", [square_border(), crease])


def curved_pleats() -> str:
    """Five parallel S-shaped creases, alternating mountain/valley, 108°."""
    body = [square_border()]
    for k, x in enumerate((25, 50, 75, 100, 125)):
        stroke = MOUNTAIN if k % 2 == 0 else VALLEY
        d = f"M {x} 0 c -18 37.5 -18 37.5 0 75 s 18 37.5 0 75"
        body.append(_path(d, stroke, 0.6, f"pleat{k + 1}"))
    return _svg("curved pleats: five S-shaped creases, alternating M/V, 108 degrees", body)


def _annular_sector(assignments: list[str], title: str) -> str:
    """Quarter annulus (centre at the sheet's bottom-left corner) with concentric circular-arc creases."""
    cx, cy, r_in, r_out = 5.0, 145.0, 35.0, 140.0
    border = (
        f"M {cx + r_in:g} {cy:g} L {cx + r_out:g} {cy:g} "
        f"A {r_out:g} {r_out:g} 0 0 0 {cx:g} {cy - r_out:g} "
        f"L {cx:g} {cy - r_in:g} "
        f"A {r_in:g} {r_in:g} 0 0 1 {cx + r_in:g} {cy:g} Z"
    )
    body = [_path(border, BORDER, ident="border")]
    n = len(assignments)
    for k, a in enumerate(assignments):
        r = r_in + (r_out - r_in) * (k + 1) / (n + 1)
        d = f"M {cx + r:g} {cy:g} A {r:g} {r:g} 0 0 0 {cx:g} {cy - r:g}"
        body.append(_path(d, MOUNTAIN if a == "M" else VALLEY, 0.6, f"arc{k + 1}"))
    return _svg(title, body)


def concentric_arcs() -> str:
    """Annular sector with three concentric circular-arc creases, alternating M/V/M."""
    return _annular_sector(["M", "V", "M"], "concentric circular arcs, alternating M/V, 108 degrees")


def cannot_fold() -> str:
    """The same sector with every arc a mountain: it cannot fold as assigned (paper Fig. 7)."""
    return _annular_sector(["M", "M", "M"], "concentric arcs all mountains: cannot fold as assigned (paper Fig. 7)")


def curved_border() -> str:
    """A closed Bézier border (a rounded blob) with one curved mountain crease between two border anchors."""
    k = 4.0 * (math.sqrt(2.0) - 1.0) / 3.0  # circle-like handles
    cx, cy, rx, ry = 75.0, 75.0, 68.0, 52.0
    left, right = (cx - rx, cy), (cx + rx, cy)
    top, bottom = (cx, cy - ry), (cx, cy + ry)
    d = (
        f"M {right[0]:g} {right[1]:g} "
        f"C {right[0]:g} {cy - k * ry:.4f} {cx + k * rx * 1.2:.4f} {top[1]:g} {top[0]:g} {top[1]:g} "
        f"C {cx - k * rx * 0.8:.4f} {top[1]:g} {left[0]:g} {cy - k * ry:.4f} {left[0]:g} {left[1]:g} "
        f"C {left[0]:g} {cy + k * ry:.4f} {cx - k * rx * 1.2:.4f} {bottom[1]:g} {bottom[0]:g} {bottom[1]:g} "
        f"C {cx + k * rx * 0.8:.4f} {bottom[1]:g} {right[0]:g} {cy + k * ry:.4f} {right[0]:g} {right[1]:g} Z"
    )
    crease = f"M {left[0]:g} {left[1]:g} C 40 45 110 105 {right[0]:g} {right[1]:g}"
    return _svg(
        "curved (Bezier) border with one curved mountain crease, 108 degrees",
        [_path(d, BORDER, ident="border"), _path(crease, MOUNTAIN, 0.6, "crease")],
    )


EXAMPLES = {
    "single_curve.svg": single_curve,
    "curved_pleats.svg": curved_pleats,
    "concentric_arcs.svg": concentric_arcs,
    "curved_border.svg": curved_border,
    "cannot_fold.svg": cannot_fold,
}


def main() -> None:
    for name, make in EXAMPLES.items():
        (HERE / name).write_text(make(), encoding="utf-8")
        print(f"wrote {HERE / name}")


if __name__ == "__main__":
    main()
