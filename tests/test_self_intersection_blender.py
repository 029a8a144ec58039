"""Self-intersection in Blender (issue 17): the fold object's ``cf_crossing`` colours, the count in the panel's
figures and the Crossing colour button, on a pattern whose flaps pass through each other when folded."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from .test_intersections import CROSSING_FLAPS

bpy = pytest.importorskip("bpy")

pytestmark = pytest.mark.usefixtures("extension")


def _crossing_colours(ob) -> np.ndarray:
    """Per-triangle "crossing" flag read back from the CORNER colours (red = 1 on the heat map)."""
    me = ob.data
    colours = np.empty(4 * len(me.loops), dtype=np.float32)
    me.color_attributes["cf_crossing"].data.foreach_get("color", colours)
    rgba = colours.reshape(-1, 3, 4)[:, 0]
    return (rgba[:, 0] > 0.5) & (rgba[:, 2] < 0.5)


def test_crossing_flaps_coloured_and_counted(extension, clean_scene, tmp_path):
    svg = tmp_path / "crossing_flaps.svg"
    svg.write_text(CROSSING_FLAPS)
    assert bpy.ops.curved_fold.import_pattern(filepath=str(svg)) == {"FINISHED"}
    assert bpy.ops.curved_fold.fold(fold_percent=100.0) == {"FINISHED"}
    ob = bpy.context.active_object
    count = ob["cf_self_intersecting_faces"]
    red = _crossing_colours(ob)
    assert count > 0 and int(red.sum()) == count
    # the same faces the engine finds on the stored mesh and positions
    mesh_object = importlib.import_module(f"{extension.__name__}.scene.mesh_object")
    intersections = importlib.import_module(f"{extension.__name__}.core.metrics.intersections")
    co = np.empty(3 * len(ob.data.vertices), dtype=np.float32)
    ob.data.attributes["position"].data.foreach_get("vector", co)
    mesh = mesh_object.read_fold_mesh(ob)
    mm = co.reshape(-1, 3).astype(np.float64) * mesh_object.mm_per_unit(bpy.context.scene)
    assert np.array_equal(red, intersections.intersecting_faces(mm, mesh.triangles))
    assert bpy.ops.curved_fold.show_colours(kind="CROSSING") == {"FINISHED"}
    assert ob.data.color_attributes.active_color.name == "cf_crossing"
    # at 50 % the flaps stand apart: re-solve the stored mesh, the colours and the count follow
    ob.curved_fold_mesh.fold_percent = 50.0
    assert bpy.ops.curved_fold.refold(rebuild="RESOLVE") == {"FINISHED"}
    assert ob["cf_self_intersecting_faces"] == 0 and not _crossing_colours(ob).any()
