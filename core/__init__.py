"""The Curved Fold engine: crease patterns, discretisation, ruling-aware meshing, solver, metrics, file formats.

Everything here takes and returns plain data (numpy arrays, small dataclasses) and never touches a Blender scene
or ``bpy.context``; only the edge swaps use ``bmesh`` (as the design card asks). See ``docs/architecture.md``.
"""
