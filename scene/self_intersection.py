"""Self-intersection in the viewport: colour the triangles that pass through the sheet elsewhere (issue 17).

The engine reports how many triangles cross a non-adjacent one (``core.metrics.intersections``, the report's
``self_intersecting_faces``); here the same test colours them on the fold object so a designer sees where paper
passes through paper before a render shows it:

* ``cf_crossing`` (FLOAT_COLOR, corner): red on crossing triangles, blue elsewhere (the strain/warp colour map with
  the crossing flag as value), for the viewport's Attribute colour mode;
* ``ob["cf_self_intersecting_faces"]``: the count, shown in the panel's Last Run figures.

Kept apart from ``mesh_object`` (which writes the pattern and the solve's results) as one small function.
"""

from __future__ import annotations

import bpy
import numpy as np

from ..core.mesh.fold_mesh import FoldMesh
from ..core.metrics.intersections import intersecting_faces
from . import mesh_object

ATTRIBUTE = "cf_crossing"
COUNT_KEY = "cf_self_intersecting_faces"


def write_crossing_colours(
    ob: bpy.types.Object, mesh: FoldMesh, positions: np.ndarray, crossing: np.ndarray | None = None
) -> int:
    """Colour the triangles of ``ob`` that cross a non-adjacent triangle at ``positions`` (``(n, 3)`` mm) and store
    their count on the object; returns the count (−1, and no colours, for non-finite positions). ``crossing``: the
    per-triangle mask if already measured (a job measures it in a unit of its own, before its commit)."""
    positions = np.asarray(positions, dtype=np.float64)
    if not np.all(np.isfinite(positions)):
        ob[COUNT_KEY] = -1
        return -1
    if crossing is None:
        crossing = intersecting_faces(positions, mesh.triangles)
    mesh_object.write_colours(ob.data, ATTRIBUTE, crossing.astype(np.float64), 1.0)
    count = int(np.count_nonzero(crossing))
    ob[COUNT_KEY] = count
    return count
