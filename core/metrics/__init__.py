"""Stage 4 — the measures of a folded mesh (ground truth §4): how developable and how accurate it is.

In: a :class:`..mesh.fold_mesh.FoldMesh` and folded positions (mm).
Out: per-edge/per-vertex arrays and a summary — strain, warp angle (§4.1), angle defect, simulated fold angles and
their error against the targets.

Modules: :mod:`.measures`.
"""
