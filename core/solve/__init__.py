"""Stage 3 — the fold: Origami Simulator's bar-and-hinge model, solved to equilibrium.

In: a :class:`..mesh.fold_mesh.FoldMesh`, a fold percent, solver settings (stiffnesses, method), optionally a start.
Out: a :class:`.solver.FoldResult` — folded positions (mm), simulated fold angles, iterations, residual, energy —
or, per frame, :class:`.animation.FrameResult` s.

Modules: :mod:`.model` (bars, hinges, face angles in normalised units), :mod:`.forces` (the one energy, its forces and
Hessian blocks), :mod:`.newton` (the fast solver), :mod:`.dissection` (numpy-only sparse factorisation: nested
dissection, multifrontal Cholesky), :mod:`.linalg` (the block-tridiagonal one it replaced), :mod:`.lapack` (OpenBLAS
through ctypes), :mod:`.faithful` (Origami Simulator's explicit dynamics), :mod:`.solver` (the public API),
:mod:`.animation` (fold percent per frame).
"""
