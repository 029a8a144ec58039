"""Pins and glue in Blender (issue 17): the ``cf_pins`` vertex group and hook empties hold vertices, the
``cf_glue_a``/``cf_glue_b`` groups close a strip into a tube on re-solve, and a moved hook re-solves a live fold."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from .test_pins_glue import STRIP_H, STRIP_W, strip_svg

bpy = pytest.importorskip("bpy")

pytestmark = pytest.mark.usefixtures("extension")


def _mod(extension, name):
    return importlib.import_module(f"{extension.__name__}.{name}")


@pytest.fixture
def strip(extension, clean_scene, tmp_path):
    svg = tmp_path / "strip.svg"
    svg.write_text(strip_svg())
    assert bpy.ops.curved_fold.import_pattern(filepath=str(svg)) == {"FINISHED"}
    assert bpy.ops.curved_fold.fold(fold_percent=100.0) == {"FINISHED"}
    return bpy.context.active_object


def _flat(ob) -> np.ndarray:
    flat = np.empty(2 * len(ob.data.vertices), np.float32)
    ob.data.attributes["cf_flat"].data.foreach_get("vector", flat)
    return flat.reshape(-1, 2).astype(np.float64)


def _nearest(flat: np.ndarray, x: float, y: float) -> int:
    return int(np.argmin(np.linalg.norm(flat - (x, y), axis=1)))


def test_glue_groups_close_the_strip(strip, extension):
    ob = strip
    pins = _mod(extension, "scene.pins")
    flat = _flat(ob)
    a = [_nearest(flat, 0.0, 0.0), _nearest(flat, 0.0, -STRIP_H)]
    b = [_nearest(flat, STRIP_W, -STRIP_H), _nearest(flat, STRIP_W, 0.0)]  # order in the group does not matter
    ob.vertex_groups.new(name="cf_glue_a").add(a, 1.0, "REPLACE")
    ob.vertex_groups.new(name="cf_glue_b").add(b, 1.0, "REPLACE")
    before = pins.current_positions(ob)
    assert np.linalg.norm(before[a[0]] - before[b[1]]) > 20.0  # open: the creases stop 5° short of a tube
    assert bpy.ops.curved_fold.refold(rebuild="RESOLVE") == {"FINISHED"}
    after = pins.current_positions(ob)
    diagonal = float(np.hypot(STRIP_W, STRIP_H))
    assert np.linalg.norm(after[a[0]] - after[b[1]]) <= 1e-5 * diagonal  # float32 vertex storage
    assert np.linalg.norm(after[a[1]] - after[b[0]]) <= 1e-5 * diagonal
    assert 0.0 <= ob["cf_glue_gap_mm"] <= 1e-6 * diagonal
    ob.vertex_groups.remove(ob.vertex_groups["cf_glue_b"])
    with pytest.raises(RuntimeError, match="same number of vertices"):
        bpy.ops.curved_fold.refold(rebuild="RESOLVE")


def test_a_bake_folds_with_the_glue(strip, extension):
    """The frames of a bake (and of playback) fold with the object's pins and glue, as Re-fold does: the strip's
    glued ends meet in the last baked frame. A bake animated the free fold before, the ends 18 mm apart in a
    helper's session, without a word."""
    ob = strip
    pins = _mod(extension, "scene.pins")
    flat = _flat(ob)
    a = [_nearest(flat, 0.0, 0.0), _nearest(flat, 0.0, -STRIP_H)]
    b = [_nearest(flat, STRIP_W, 0.0), _nearest(flat, STRIP_W, -STRIP_H)]
    ob.vertex_groups.new(name="cf_glue_a").add(a, 1.0, "REPLACE")
    ob.vertex_groups.new(name="cf_glue_b").add(b, 1.0, "REPLACE")
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 8
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    scene.frame_set(8)
    last = pins.current_positions(ob.evaluated_get(bpy.context.evaluated_depsgraph_get()))
    diagonal = float(np.hypot(STRIP_W, STRIP_H))
    assert np.linalg.norm(last[a[0]] - last[b[0]]) <= 1e-4 * diagonal
    assert np.linalg.norm(last[a[1]] - last[b[1]]) <= 1e-4 * diagonal


def test_pin_group_and_hook_empties(strip, extension):
    ob = strip
    pins = _mod(extension, "scene.pins")
    live = _mod(extension, "scene.live")
    flat = _flat(ob)
    corner = _nearest(flat, 0.0, 0.0)
    other = _nearest(flat, STRIP_W, 0.0)
    ob.vertex_groups.new(name="cf_pins").add([corner, other], 1.0, "REPLACE")
    held_before = pins.current_positions(ob)[corner]
    # fold further: the pinned vertices stay where they were
    ob.curved_fold_mesh.fold_percent = 60.0
    assert bpy.ops.curved_fold.refold(rebuild="RESOLVE") == {"FINISHED"}
    assert np.linalg.norm(pins.current_positions(ob)[corner] - held_before) <= 1e-3  # float32 mm
    assert bpy.ops.curved_fold.add_pin_hooks() == {"FINISHED"}
    hooks = pins.pin_hooks(ob)
    assert sorted(hooks) == sorted([corner, other])
    # drag the corner's hook 10 mm up: with Live on, the depsgraph handler queues a re-solve that follows it
    ob.curved_fold_mesh.live = True
    live._pending.clear()
    mm = _mod(extension, "scene.mesh_object").mm_per_unit(bpy.context.scene)
    hooks[corner].location.z += 10.0 / mm
    bpy.context.view_layer.update()
    assert list(live._pending) == [ob.name] and live._pending[ob.name][1] is False
    assert live.run_pending() == {ob.name: "ok"}
    target = np.array(hooks[corner].location) * mm
    assert np.linalg.norm(pins.current_positions(ob)[corner] - target) <= 1e-3
    ob.curved_fold_mesh.live = False


def test_glue_selected_pair_in_edit_mode(view3d, strip, extension):
    ob = strip
    pins = _mod(extension, "scene.pins")
    flat = _flat(ob)
    a, b = _nearest(flat, 0.0, 0.0), _nearest(flat, STRIP_W, 0.0)
    import bmesh

    with bpy.context.temp_override(**view3d):
        bpy.ops.object.mode_set(mode="EDIT")
        bm = bmesh.from_edit_mesh(ob.data)
        for element in (*bm.faces, *bm.edges, *bm.verts):
            element.select = False
        bm.verts.ensure_lookup_table()
        bm.verts[a].select = True
        bm.verts[b].select = True
        bmesh.update_edit_mesh(ob.data)
        assert bpy.ops.curved_fold.glue_selected() == {"FINISHED"}
        bpy.ops.object.mode_set(mode="OBJECT")
    assert pins.glue_pairs(ob).tolist() == [[min(a, b), max(a, b)]]
    assert bpy.ops.curved_fold.refold(rebuild="RESOLVE") == {"FINISHED"}
    after = pins.current_positions(ob)
    assert np.linalg.norm(after[a] - after[b]) <= 1e-5 * float(np.hypot(STRIP_W, STRIP_H))
    assert bpy.ops.curved_fold.clear_glue() == {"FINISHED"} and len(pins.glue_pairs(ob)) == 0
