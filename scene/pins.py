"""Pins and glue on a fold object (issue 17): vertex groups and hook empties → ``core.solve.constraints``.

* ``cf_pins`` vertex group: the vertices held where they are when the mesh is re-solved (the solve warm-starts from
  the current shape, so "where they are" is the shape on screen);
* hook empties (:func:`add_pin_hooks`, children of the fold object with ``cf_pin_vertex`` = vertex index): the pinned
  vertex follows its empty; with Live on, moving an empty re-solves the fold (:func:`on_depsgraph_update`, debounced
  by ``scene.live``);
* ``cf_glue_a`` / ``cf_glue_b`` vertex groups: glued pairs, the k-th vertex of one to the k-th of the other, each
  group ordered along its own longest flat extent (two edges of the sheet glue end to end, a single vertex to a
  single vertex);
* ``ob["cf_glue_pairs"]``: pairs picked in the viewport (:func:`add_glue_pair`, the Glue Selected operator).

Pins and glue act when the stored mesh is re-solved (fold percent, Re-fold → Re-solve, hooks); rebuilding the mesh
from the curves makes new vertices and leaves the groups behind.
"""

from __future__ import annotations

import bpy
import numpy as np
from bpy.app.handlers import persistent

from ..core.mesh.fold_mesh import FoldMesh
from ..core.pattern.model import PatternError
from ..core.solve.constraints import Constraints
from . import app_handlers, mesh_object

PIN_GROUP = "cf_pins"
GLUE_GROUPS = ("cf_glue_a", "cf_glue_b")
HOOK_VERTEX = "cf_pin_vertex"
GAP_KEY = "cf_glue_gap_mm"
PAIRS_KEY = "cf_glue_pairs"


def glue_pairs(ob: bpy.types.Object) -> np.ndarray:
    """The picked glue pairs of ``ob`` ``(g, 2)`` (stored flat as ``[a0, b0, a1, b1, ...]``)."""
    return np.array(list(ob.get(PAIRS_KEY, [])), dtype=np.int64).reshape(-1, 2)


def add_glue_pair(ob: bpy.types.Object, a: int, b: int) -> int:
    """Glue vertices ``a`` and ``b`` of ``ob`` (kept on the object); returns the number of picked pairs."""
    if a == b:
        raise PatternError("pick two different vertices to glue")
    pairs = glue_pairs(ob).tolist()
    if [a, b] not in pairs and [b, a] not in pairs:
        pairs.append([int(a), int(b)])
    ob[PAIRS_KEY] = [int(v) for pair in pairs for v in pair]
    return len(pairs)


def group_vertices(ob: bpy.types.Object, name: str) -> np.ndarray:
    """Indices of the vertices in ``ob``'s vertex group ``name`` with a weight > 0 (empty if there is no group)."""
    group = ob.vertex_groups.get(name)
    if group is None:
        return np.zeros(0, dtype=np.int64)
    k = group.index
    return np.array(
        [v.index for v in ob.data.vertices if any(g.group == k and g.weight > 0 for g in v.groups)], dtype=np.int64
    )


def pin_hooks(ob: bpy.types.Object) -> dict[int, bpy.types.Object]:
    """Hook empties of ``ob``: vertex index → empty."""
    return {int(c[HOOK_VERTEX]): c for c in ob.children if c.type == "EMPTY" and HOOK_VERTEX in c}


def current_positions(ob: bpy.types.Object, scene: bpy.types.Scene | None = None) -> np.ndarray:
    """The fold object's vertex positions as shown (``(n, 3)`` mm, the engine's frame: object space less any move
    of its origin, ``mesh_object.engine_positions``)."""
    return mesh_object.engine_positions(ob, scene)


def _along(flat: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``idx`` ordered along the longest extent of their flat positions."""
    if len(idx) < 2:
        return idx
    p = flat[idx]
    axis = int(np.argmax(np.ptp(p, axis=0)))
    return idx[np.argsort(p[:, axis], kind="stable")]


def constraints_from_object(
    ob: bpy.types.Object, mesh: FoldMesh, scene: bpy.types.Scene | None = None
) -> Constraints | None:
    """The pins (group + hooks) and glue (two groups) of ``ob`` on ``mesh``'s vertices, or None when it has none."""
    pinned = set(group_vertices(ob, PIN_GROUP).tolist())
    hooks = {k: e for k, e in pin_hooks(ob).items() if 0 <= k < mesh.n_vertices}
    pins = np.array(sorted(pinned | set(hooks)), dtype=np.int64)
    targets = np.full((len(pins), 3), np.nan)
    if hooks:
        to_local = ob.matrix_world.inverted()
        mm = mesh_object.mm_per_unit(scene)
        offset = mesh_object.local_offset(ob)  # object space less any move of its origin: the engine's frame
        for row, k in enumerate(pins.tolist()):
            if k in hooks:
                targets[row] = (np.array(to_local @ hooks[k].matrix_world.translation) - offset) * mm
    a, b = (group_vertices(ob, name) for name in GLUE_GROUPS)
    if len(a) != len(b):
        raise PatternError(
            f"'{ob.name}': glue groups {GLUE_GROUPS[0]} ({len(a)} vertices) and {GLUE_GROUPS[1]} ({len(b)}) must hold "
            "the same number of vertices (the k-th of one is glued to the k-th of the other)"
        )
    glue = np.column_stack([_along(mesh.vertices, a), _along(mesh.vertices, b)]) if len(a) else np.zeros((0, 2))
    glue = np.concatenate([np.asarray(glue, dtype=np.int64).reshape(-1, 2), glue_pairs(ob)])
    held = Constraints(pins, targets, glue)
    if held.empty:
        return None
    held.check(mesh.n_vertices)
    return held


def store_figures(ob: bpy.types.Object, report: dict) -> None:
    """Keep the last run's largest glue gap (mm) on the object for the panel (−1 without glue)."""
    gap = report.get("glue_gap_max_mm")
    ob[GAP_KEY] = float(gap) if gap is not None else -1.0


def add_pin_hooks(ob: bpy.types.Object, scene: bpy.types.Scene | None = None) -> list[bpy.types.Object]:
    """An empty (child of ``ob``) at every vertex of the ``cf_pins`` group that has none yet; returns the new ones.

    Moving an empty moves its vertex's pin target; the fold follows on the next re-solve (live when Live is on)."""
    vertices = group_vertices(ob, PIN_GROUP)
    if len(vertices) == 0:
        raise PatternError(f"'{ob.name}' has no '{PIN_GROUP}' vertex group with vertices: assign the vertices to pin")
    have = pin_hooks(ob)
    co = mesh_object.local_coordinates(ob)  # object space: the empties are its children
    size = 0.02 * float(np.max(np.ptp(co, axis=0))) or 0.01
    collection = ob.users_collection[0] if ob.users_collection else bpy.context.scene.collection
    made = []
    for k in vertices.tolist():
        if k in have:
            continue
        empty = bpy.data.objects.new(f"{ob.name} Pin {k}", None)
        empty.empty_display_type = "SPHERE"
        empty.empty_display_size = size
        empty[HOOK_VERTEX] = k
        collection.objects.link(empty)
        empty.parent = ob
        empty.location = tuple(co[k])
        made.append(empty)
    return made


@persistent
def on_depsgraph_update(scene, depsgraph) -> None:
    """A moved hook empty of a live fold object schedules a re-solve (debounced; no work here)."""
    from . import live

    for update in depsgraph.updates:
        id_ = update.id.original if hasattr(update.id, "original") else update.id
        if not isinstance(id_, bpy.types.Object) or id_.type != "EMPTY" or HOOK_VERTEX not in id_:
            continue
        parent = id_.parent
        props = getattr(parent, "curved_fold_mesh", None) if parent is not None else None
        if props is not None and props.is_fold_mesh and props.live and update.is_updated_transform:
            live.schedule_refold(parent.name, rebuild=False)


def register_extra() -> None:
    app_handlers.attach(bpy.app.handlers.depsgraph_update_post, on_depsgraph_update)


def unregister_extra() -> None:
    app_handlers.detach(bpy.app.handlers.depsgraph_update_post, on_depsgraph_update)
