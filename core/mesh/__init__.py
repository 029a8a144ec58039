"""Stage 2 — the mesh: constrained Delaunay triangulation without interior points (paper §3.2) and the greedy
edge swaps that make edges follow the estimated rulings (§3.3).

In: a discretised :class:`..pattern.model.CreasePattern`.
Out: a :class:`.fold_mesh.FoldMesh` — flat vertices, triangles, edges with their crease assignment and target fold
angle — for the solver.

Modules: :mod:`.triangulate` (§3.2, ``triangle`` or ``mathutils`` backends), :mod:`.ruling` (§3.3 swaps on a
``bmesh``), :mod:`.squash` (then flips away the caps the fold could press flat; not in the paper), :mod:`.earcut`
(Origami Simulator's ear clipping, a baseline), :mod:`.build` (pattern → mesh by mesh type, timed),
:mod:`.fold_mesh` (the mesh's arrays), :mod:`.transfer` (a folded shape carried onto a re-meshed pattern: the warm
start of a live re-fold).
"""
