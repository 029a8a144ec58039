"""Frozen copy of the straightforward mesh generation (commit 0771976), used only by tests/test_mesh_reference.py.

The optimised ``core.triangulate``, ``core.ruling``, ``core.earcut`` and ``core.meshing`` must give exactly the same
meshes as this reference on every fixture and example. Do not optimise this copy: it is the yardstick.
"""
