"""Squash flips: no triangle that the fold can press flat for free (issue 12, "no kinks").

A constrained Delaunay triangulation without interior points (paper §3.2) maximises the smallest corner, not the
largest. Where a curved crease bends away from everything near it, its consecutive nodes are nearly cocircular with
nothing inside their circle, and the CDT fills the concave side with *caps*: triangles of three curve nodes (or a fan
of them from the curve's next crossing) whose middle corner is 172–179.5°. Folding the crease bends its nodes out of
the plane (κ₃D = κ₂D / cos(ρ/2)), which a rigid cap forbids, so the fold presses the cap onto its long side and
through it: the solver then crawls over a fold angle that flips by 180° across a height of ~1e-9 (straight pleats
crossing a curve at 1 mm: 200 iterations, not converged, 7 s for 1,308 faces).

What makes a triangle easy to press flat is not a small corner but a small *squash strain*: the relative length
change of its sides that puts its three corners on one line, ``(l₁ + l₂ − l₃) / l₃`` with ``l₃`` the longest side
(:func:`squash_strain`). It is second order for a cap (≈ δ²/8 for a corner of 180° − δ: 2.9e-5 at 179.1°) and first
order for a needle (≈ sin α for a corner α: a needle's short side has to turn). So the mesh keeps needles, which the
CDT forces between a fine curve and a far crease, and removes caps where it can: the shared edge of a pair of
triangles whose smaller squash strain is below :data:`SQUASH_STRAIN` is flipped when that at least doubles it
(:data:`SQUASH_GAIN`; Lawson's flip loop on that measure, pattern segments never flipped, strictly convex quads
only), so the loop ends. The flips cascade from the far end of a fan of caps, which is why the loop works on edges
and re-queues the quad's four sides after each flip. Caps that no flip removes stay: every triangulation of a fine
circle's nodes without interior points has some (its two ears at least, 180° − 360°/N); the hinge's fading
stiffness (``core.solve.forces.flat_attenuation``) keeps the energy smooth when the fold presses one flat.
"""

from __future__ import annotations

import math

import numpy as np

from .triangulate import _orient2

SQUASH_STRAIN = 1e-3
"""Triangles whose squash strain is below this are flipped away where a flip raises it: a cap with a corner above
~175° (isosceles: 175° → 9.5e-4) or a needle with a corner below ~0.06°.

Fold strains are 1e-3–1e-2 (mean 0.1–0.2 %, max ~1 % on the fixtures): a triangle that is pressed flat within that
range is pressed flat by folding. 1e-3 is where the caps that stalled the solver start (issue 12's crossing pleats,
tangent circles); above it the CDT's needles dominate (a 1 mm chord seen from a crease 100 mm away has 1e-2), and a
flip cannot raise those (the CDT already maximises the smallest corner)."""


SQUASH_GAIN = 2.0
"""A flip is made only when it at least doubles the pair's smaller squash strain. Points along a fine curve are
nearly cocircular, and every triangulation of them has caps: accepting any rise, the loop shuffled them (a wave at
0.04 mm chords: 102,266 flips, the smallest strain 4.88e-7 → 4.94e-7, +1 s; with the doubling none); the caps
that a far vertex can replace gain 10–100× per flip."""


def squash_strain(p: list[float], q: list[float], r: list[float]) -> float:
    """``(l₁ + l₂ − l₃) / l₃`` of triangle (p, q, r), ``l₃`` its longest side: the strain that lays it flat on a line.

    Plain floats and correctly rounded operations only (``math.sqrt``), so the same value on every machine and in
    :func:`squash_strains`.
    """
    a = math.sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]))
    b = math.sqrt((r[0] - q[0]) * (r[0] - q[0]) + (r[1] - q[1]) * (r[1] - q[1]))
    c = math.sqrt((p[0] - r[0]) * (p[0] - r[0]) + (p[1] - r[1]) * (p[1] - r[1]))
    longest = max(a, b, c)
    return (a + b + c - 2.0 * longest) / longest


def squash_strains(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """:func:`squash_strain` of every triangle at once (the same operations in the same order: the same values)."""
    p, q, r = (vertices[triangles[:, k]] for k in range(3))

    def side(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.sqrt((v[:, 0] - u[:, 0]) * (v[:, 0] - u[:, 0]) + (v[:, 1] - u[:, 1]) * (v[:, 1] - u[:, 1]))

    a, b, c = side(p, q), side(q, r), side(r, p)
    longest = np.maximum(np.maximum(a, b), c)
    return (((a + b) + c) - 2.0 * longest) / longest


def squash_flips(
    vertices: np.ndarray,
    tris: list[list[int]],
    triangle_face: list[int],
    constrained: set[int],
    threshold: float = SQUASH_STRAIN,
) -> list[tuple[int, ...]]:
    """Flip edges until no pair of triangles below ``threshold`` can raise its smaller squash strain by a flip.

    ``tris``: CCW triangles as lists, changed in place (a flipped quad keeps its two slots); ``constrained``: the
    pattern segments as codes ``min·n + max`` (never flipped). A flip must at least double (:data:`SQUASH_GAIN`)
    the smaller squash strain of its pair, so the loop ends. Returns the flips as ``(a, c, b, d, t1, t2, f)`` —
    edge ac became bd, t1 = (a, c, b) became (a, d, b) and t2 = (c, a, d) became (d, c, b), f their crease-pattern
    face — the records :func:`..ruling._apply_with_bmesh_steps` applies.
    """
    n = len(vertices)
    if not tris:
        return []
    strain = squash_strains(vertices, np.asarray(tris, dtype=np.int64)).tolist()
    xy = vertices.tolist()
    owner: dict[int, int] = {}
    for ti, (x, y, z) in enumerate(tris):
        owner[x * n + y] = ti
        owner[y * n + z] = ti
        owner[z * n + x] = ti
    stack: list[tuple[int, int]] = []
    for ti in np.flatnonzero(np.asarray(strain) < threshold).tolist():
        x, y, z = tris[ti]
        stack += [(x, y), (y, z), (z, x)]
    flips: list[tuple[int, ...]] = []
    limit = 50 * len(tris) + 100
    while stack:
        a, c = stack.pop()
        if (a * n + c if a < c else c * n + a) in constrained:
            continue
        t1, t2 = owner.get(a * n + c, -1), owner.get(c * n + a, -1)
        if t1 < 0 or t2 < 0:
            continue
        old = min(strain[t1], strain[t2])
        if old >= threshold:
            continue
        tr1, tr2 = tris[t1], tris[t2]
        b = tr1[0] + tr1[1] + tr1[2] - a - c
        d = tr2[0] + tr2[1] + tr2[2] - a - c
        pa, pb, pc, pd = xy[a], xy[b], xy[c], xy[d]
        if _orient2(pa, pd, pb) <= 0 or _orient2(pd, pc, pb) <= 0:  # quad a, d, c, b not strictly convex
            continue
        s1, s2 = squash_strain(pa, pd, pb), squash_strain(pd, pc, pb)
        if min(s1, s2) <= SQUASH_GAIN * old:
            continue
        if len(flips) >= limit:  # pragma: no cover - every flip raises a pair's minimum; guard all the same
            raise RuntimeError("mesh: squash flips did not terminate")
        for x, y, z in (tr1, tr2):
            del owner[x * n + y], owner[y * n + z], owner[z * n + x]
        tris[t1], tris[t2] = [a, d, b], [d, c, b]
        strain[t1], strain[t2] = s1, s2
        for ti in (t1, t2):
            x, y, z = tris[ti]
            owner[x * n + y] = ti
            owner[y * n + z] = ti
            owner[z * n + x] = ti
        flips.append((a, c, b, d, t1, t2, triangle_face[t1]))
        stack += [(a, d), (d, c), (c, b), (b, a)]
    return flips
