"""Render the operator pictures: a curved-crease pattern at three fold percents, and the strain colours.

Runs headless through the add-on's own operators (Import Crease Pattern, Fold, Re-fold) in the bpy module:

    .venv/bin/python docs/img/make_pictures.py [pattern.svg]

writes ``docs/img/fold_percent.png``, ``docs/img/strain.png`` and ``docs/img/warp.png`` (Workbench, 8× AA; no GPU
needed beyond Mesa's llvmpipe). The default pattern is Origami Simulator's ``wavy_pleats.svg``
(vendored in ``tests/fixtures``).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import bpy
import numpy as np

HERE = Path(__file__).resolve().parent
FIXTURE = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "origami-simulator" / "wavy_pleats.svg"


def setup_addon():
    import curved_fold

    bpy.ops.wm.read_factory_settings(use_empty=True)
    curved_fold.register()


def camera_for(objects, direction=(0.55, -1.0, 0.75), lens=50.0, margin=1.15):
    """A camera looking at the objects' bounding box from ``direction``."""
    pts = np.array([ob.matrix_world @ v.co for ob in objects for v in ob.data.vertices])
    centre = 0.5 * (pts.min(0) + pts.max(0))
    radius = 0.5 * np.linalg.norm(pts.max(0) - pts.min(0)) * margin
    d = np.array(direction, float)
    d /= np.linalg.norm(d)
    cam_data = bpy.data.cameras.new("Camera")
    cam_data.lens = lens
    cam = bpy.data.objects.new("Camera", cam_data)
    bpy.context.scene.collection.objects.link(cam)
    dist = radius / math.tan(cam_data.angle / 2)
    cam.location = centre + d * dist
    from mathutils import Vector

    cam.rotation_euler = (Vector(centre) - Vector(cam.location)).to_track_quat("-Z", "Y").to_euler()
    cam_data.clip_start, cam_data.clip_end = dist * 0.01, dist * 10
    bpy.context.scene.camera = cam
    return cam


def render(path: Path, colour_type: str, width=1200, height=500):
    scene = bpy.context.scene
    scene.render.engine = "BLENDER_WORKBENCH"
    shading = scene.display.shading
    shading.light = "STUDIO"
    shading.color_type = colour_type
    shading.show_cavity = False
    shading.show_object_outline = False
    shading.show_backface_culling = False
    scene.display.render_aa = "8"
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.film_transparent = False
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = str(path)
    world = bpy.data.worlds.new("World") if scene.world is None else scene.world
    scene.world = world
    world.color = (1, 1, 1)
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    print(f"rendered {path.name} in {time.perf_counter() - t:.1f} s")


def main(pattern: Path) -> None:
    setup_addon()
    assert bpy.ops.curved_fold.import_pattern(filepath=str(pattern)) == {"FINISHED"}
    curves = list(bpy.context.selected_objects)
    for ob in curves:
        ob.hide_render = True
    folds = []
    size = None
    for k, pct in enumerate((30.0, 60.0, 90.0)):
        for ob in bpy.context.view_layer.objects:
            ob.select_set(ob in curves)
        bpy.context.view_layer.objects.active = curves[0]
        assert bpy.ops.curved_fold.fold(fold_percent=pct) == {"FINISHED"}
        ob = bpy.context.active_object
        props = ob.curved_fold_mesh
        print(
            f"{pct:.0f} %: {props.last_faces} faces, {props.last_ms:.0f} ms, {props.last_iterations} it., "
            f"strain {props.last_strain_mean:.3f} % mean / {props.last_strain_max:.3f} % max, "
            f"warp {props.last_warp_mean:.3f}°, converged {props.last_converged}"
        )
        co = np.array([v.co for v in ob.data.vertices])
        size = size or float(np.ptp(co[:, 0]))
        ob.location = (k * 1.25 * size - ob.matrix_world.translation.x + ob.location.x - co[:, 0].min(), 0, 0)
        ob.color = (0.93, 0.9, 0.82, 1)
        folds.append(ob)
    bpy.context.view_layer.update()
    camera_for(folds)
    render(HERE / "fold_percent.png", "OBJECT")
    # Strain colours of the 90 % fold: the cf_strain point colours (Origami Simulator's map, blue 0 → red 5 %).
    for ob in folds[:-1]:
        ob.hide_render = True
        for child in ob.children:
            child.hide_render = True
    bpy.data.objects.remove(bpy.context.scene.camera)
    camera_for([folds[-1]], margin=1.05)
    me = folds[-1].data
    me.color_attributes.active_color = me.color_attributes["cf_strain"]
    render(HERE / "strain.png", "VERTEX", width=900, height=650)
    me.color_attributes.active_color = me.color_attributes["cf_warp"]  # warp angle per triangle, blue 0° → red 10°
    render(HERE / "warp.png", "VERTEX", width=900, height=650)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else FIXTURE)
