"""Stage 1 — the crease pattern: what a designer drew, and its discretisation (paper §3.1).

In: crease curves (:class:`.model.CreaseCurve`: Bézier pieces, arcs, lines, each with a role — border, mountain,
valley, cut, facet, undriven — and a fold angle), from any reader in :mod:`..io` or from Blender's curve objects.
Out: a :class:`.model.CreasePattern` — straight segments through shared vertices, planar (crossings split, near
points merged), each segment carrying its role and fold angle — ready for triangulation.

Modules: :mod:`.model` (the data and :class:`.model.PatternError`), :mod:`.discretize` (§3.1 chords within a
tolerance, then the planar clean-up), :mod:`.polylines` (segments chained back into polylines).
"""
