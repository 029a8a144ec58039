"""Render ``docs/img/textured_fold.png``: an image printed on the sheet follows the fold, seen in a glTF file.

Headless, in the bpy module: fold Origami Simulator's ``Rotating_Star.svg`` at 30/60/90 %, export the three frames as
a glTF binary with ``scene.export.export_folded_file`` (UVs from the flat crease pattern, a double-sided paper
material, morph targets with normals), then start an empty scene, import that file with Blender's glTF importer (so
the picture shows what a viewer reads from the file, not our scene), put a generated image on the material, and
render the flat sheet beside the last morph target with Workbench's texture colours (Mesa's llvmpipe is enough):

    .venv/bin/python docs/img/make_textured.py [pattern.svg]
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import bpy
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
FIXTURE = HERE.parents[1] / "tests" / "fixtures" / "origami-simulator" / "Rotating_Star.svg"


def print_image(size: int = 1024) -> bpy.types.Image:
    """A test print: checkerboard in two paper tones, a colour wheel of rays and rings (so bending and stretching
    show), generated here rather than loaded."""
    y, x = (np.mgrid[0:size, 0:size] + 0.5) / size
    check = ((np.floor(x * 12) + np.floor(y * 12)) % 2)[..., None]
    rgb = np.where(check > 0, [0.95, 0.93, 0.86], [0.80, 0.84, 0.90])
    r = np.hypot(x - 0.5, y - 0.5)
    a = np.arctan2(y - 0.5, x - 0.5)
    hue = (a / (2 * np.pi)) % 1.0
    wheel = np.stack([np.abs(hue * 6 - 3) - 1, 2 - np.abs(hue * 6 - 2), 2 - np.abs(hue * 6 - 4)], -1).clip(0, 1)
    rays = (np.cos(a * 24) > 0.6)[..., None] & (r < 0.48)[..., None]
    rings = (np.abs((r * 20) % 1 - 0.5) < 0.08)[..., None] & (r < 0.48)[..., None]
    rgb = np.where(rays, 0.35 + 0.6 * wheel, rgb)
    rgb = np.where(rings, [0.1, 0.1, 0.15], rgb)
    img = bpy.data.images.new("print", size, size)
    img.pixels.foreach_set(np.concatenate([rgb, np.ones((size, size, 1))], -1).astype(np.float32).ravel())
    img.pack()
    return img


def main(pattern: Path) -> None:
    from make_pictures import camera_for, render

    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.pipeline import fold_pattern
    from curved_fold.scene import export

    bpy.ops.wm.read_factory_settings(use_empty=True)
    t = time.perf_counter()
    cp = read_pattern(pattern)
    runs = [fold_pattern(cp, percent=p) for p in (0.3, 0.6, 0.9)]
    print(f"{pattern.name}: {runs[-1].mesh.n_faces} faces, three folds in {time.perf_counter() - t:.1f} s")
    glb = Path(tempfile.mkdtemp()) / "textured.glb"
    export.export_folded_file(glb, runs[-1].mesh, [r.result.positions for r in runs], name="Star")

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=str(glb))
    flat = next(ob for ob in bpy.context.scene.objects if ob.type == "MESH")
    mat = flat.active_material
    assert mat is not None and flat.data.uv_layers, "the glTF file lost its material or UVs"
    nodes = mat.node_tree.nodes
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = print_image()
    bsdf = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    mat.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    nodes.active = tex
    folded = flat.copy()
    folded.data = flat.data.copy()
    bpy.context.scene.collection.objects.link(folded)
    keys = folded.data.shape_keys.key_blocks
    for kb in keys[1:]:
        kb.value = 0.0
    keys[-1].value = 1.0
    for kb in flat.data.shape_keys.key_blocks[1:]:
        kb.value = 0.0
    if flat.animation_data:
        flat.animation_data_clear()
    if folded.animation_data:
        folded.animation_data_clear()
    for sk in (flat.data.shape_keys, folded.data.shape_keys):
        if sk.animation_data:
            sk.animation_data_clear()
    width = flat.dimensions.x
    flat.location.x -= 0.62 * width
    folded.location.x += 0.62 * width
    bpy.context.view_layer.update()
    camera_for([flat, folded], direction=(0.25, -1.0, 0.9), margin=1.05)
    render(HERE / "textured_fold.png", "TEXTURE", width=1200, height=560)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else FIXTURE)
