"""Files in and out: the pipeline's boundary with other tools.

In: files — SVG in Origami Simulator's colour convention (:mod:`.svg`), FOLD (:mod:`.fold`), .blend crease curves
(through the reader the Blender layer registers) — and, for the writers, a
:class:`..mesh.fold_mesh.FoldMesh` with folded positions.
Out: crease curves or a :class:`..pattern.model.CreasePattern`
(:mod:`.reader` dispatches on the suffix); FOLD files written atomically (:mod:`.atomic`).

This stage comes after the others in import order: readers build patterns, writers take meshes and results.
"""
