"""Crumpling test patterns for the solver (docs/solver.md, "Rescue of crumpling folds"): curved Miura grids and a
four-turn spiral.

Usage (from the repo root)::

    .venv/bin/python tools/crumpling_patterns.py OUT_DIR

writes ``cmiura_RxC_oNN.svg`` for R×C in 1×2, 3×6, 4×8, 6×12 at opacity 1.0 and 0.8 (180° and 144°), and
``spiral4.svg``. A grid has R rows of sine creases (amplitude 8 mm, period 40 mm, 25 mm apart, alternately mountain
and valley) on a sheet 20·C mm wide, crossed at their crests and troughs (every 20 mm from x = 10) by straight
creases whose segments alternate M/V, so that every crossing is 3–1 as in a Miura. ``cmiura_3x6_o100.svg`` is
``tests/data/sine_rows_crossed.svg`` path for path. The spiral is one Archimedean mountain crease of four turns
(radius 1 → 56 mm) in a 120 mm square. Curves are Catmull–Rom cubic Béziers through 24 points per period (48 per
turn), as the designer's files are.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

RED, BLUE = "#ff0000", "#0000ff"


def _f(v: float) -> str:
    return f"{v:.4f}"


def _catmull_rom(points: list[tuple[float, float]]) -> str:
    """SVG path data through ``points``: cubic Béziers with Catmull–Rom tangents (one-sided at the ends)."""
    n = len(points) - 1
    d = f"M {_f(points[0][0])} {_f(points[0][1])}"
    for i in range(n):
        p0, p1 = points[i], points[i + 1]
        pm, pp = points[max(i - 1, 0)], points[min(i + 2, n)]
        c1 = (p0[0] + (p1[0] - pm[0]) / 6, p0[1] + (p1[1] - pm[1]) / 6)
        c2 = (p1[0] - (pp[0] - p0[0]) / 6, p1[1] - (pp[1] - p0[1]) / 6)
        d += f" C {_f(c1[0])} {_f(c1[1])} {_f(c2[0])} {_f(c2[1])} {_f(p1[0])} {_f(p1[1])}"
    return d


def _svg(width: float, height: float, paths: list[str]) -> str:
    head = [
        '<?xml version="1.0" encoding="utf-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width + 10}mm" height="{height + 10}mm" '
        f'viewBox="-5 -5 {width + 10} {height + 10}">',
        f'<path d="M 0.0000 0.0000 L {_f(width)} 0.0000 L {_f(width)} {_f(height)} L 0.0000 {_f(height)} Z" '
        'fill="none" stroke="#000000" stroke-width="0.3"/>',
    ]
    return "\n".join([*head, *paths, "</svg>"]) + "\n"


def curved_miura(rows: int, columns: int, opacity: float = 1.0, amplitude: float = 8.0, period: float = 40.0) -> str:
    """SVG of ``rows`` sine creases crossed by ``columns − 1`` straight ones at their crests and troughs."""
    width, height = period / 2 * columns, 25.0 * (rows + 1)
    style = 'fill="none" stroke="{}" stroke-width="0.3" stroke-opacity="' + str(opacity) + '"'
    paths = []
    n = int(round(width / period * 24))
    for i in range(rows):
        y0 = 25.0 * (i + 1)
        points = [
            (width * k / n, y0 + amplitude * math.sin(2 * math.pi * (width * k / n) / period)) for k in range(n + 1)
        ]
        paths.append(f'<path d="{_catmull_rom(points)}" {style.format(RED if i % 2 == 0 else BLUE)}/>')
    for k in range(columns - 1):
        x = period / 4 + period / 2 * k
        s = math.sin(2 * math.pi * x / period)
        ys = [0.0] + [25.0 * (i + 1) + amplitude * s for i in range(rows)] + [height]
        for j in range(rows + 1):
            colour = BLUE if (j + k) % 2 == 0 else RED
            paths.append(f'<path d="M {_f(x)} {_f(ys[j])} L {_f(x)} {_f(ys[j + 1])}" {style.format(colour)}/>')
    return _svg(width, height, paths)


def spiral(opacity: float = 1.0, turns: int = 4, size: float = 120.0, r0: float = 1.0, r1: float = 56.0) -> str:
    """SVG of one Archimedean mountain crease of ``turns`` turns from radius ``r0`` to ``r1`` in a square."""
    c, n = size / 2, turns * 48
    points = []
    for i in range(n + 1):
        t, r = 2 * math.pi * turns * i / n, r0 + (r1 - r0) * i / n
        points.append((c + r * math.cos(t), c + r * math.sin(t)))
    style = f'fill="none" stroke="{RED}" stroke-width="0.3" stroke-opacity="{opacity}"'
    return _svg(size, size, [f'<path d="{_catmull_rom(points)}" {style}/>'])


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for rows, columns in ((1, 2), (3, 6), (4, 8), (6, 12)):
        for opacity in (1.0, 0.8):
            name = f"cmiura_{rows}x{columns}_o{round(opacity * 100)}.svg"
            (out / name).write_text(curved_miura(rows, columns, opacity))
    (out / "spiral4.svg").write_text(spiral())


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "out/crumpling"))
