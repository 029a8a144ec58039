"""Export a folded mesh: through Blender's own exporters (OBJ, STL, glTF with animation, .blend), as FOLD, and the
flat crease pattern as SVG in Origami Simulator's convention.

The Blender exporters run in a temporary scene holding a temporary object, so the user's scene, selection and
active object are never touched; everything temporary is removed afterwards, also on failure. Used by the Export
operator (from a folded object) and by the command line's ``fold`` for these suffixes.

Units: Blender-exported files (OBJ, STL, glTF, .blend) are in Blender units of a scene with unit scale 1, i.e.
metres (1 mm of the pattern = 0.001), which is what glTF requires and what Blender re-imports at the same size.
FOLD and SVG keep millimetres.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from pathlib import Path
from xml.sax.saxutils import quoteattr

import bpy
import numpy as np

from ..core.mesh.fold_mesh import FoldMesh

BLENDER_SUFFIXES = (".obj", ".stl", ".glb", ".gltf", ".blend")
"""Suffixes written through Blender's own exporters."""

SVG_STROKES = {"B": "#000000", "M": "#ff0000", "V": "#0000ff", "F": "#ffff00", "U": "#ff00ff", "C": "#00ff00"}
"""Origami Simulator's stroke colours per FOLD assignment (its importer matches these exactly)."""


def _frames_array(frames: np.ndarray | Sequence[np.ndarray], n: int) -> np.ndarray:
    arr = np.asarray(frames, dtype=np.float64)
    if arr.ndim == 2:
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[1:] != (n, 3) or not len(arr):
        raise ValueError(f"frames must be (n, 3) or (k, n, 3) with n = {n} vertices, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("frames contain non-finite positions")
    return arr


@contextlib.contextmanager
def temporary_scene(name: str = "Curved Fold Export") -> Iterator[bpy.types.Scene]:
    """A new scene made the window's scene for the duration; the user's scene comes back and the temporary one
    (with every object, mesh, curve, shape key and action created in it) is deleted afterwards."""
    before = {
        "objects": set(bpy.data.objects),
        "meshes": set(bpy.data.meshes),
        "curves": set(bpy.data.curves),
        "actions": set(bpy.data.actions),
        "materials": set(bpy.data.materials),
    }
    window = bpy.context.window
    previous = window.scene if window is not None else None
    scene = bpy.data.scenes.new(name)
    try:
        if window is not None:
            window.scene = scene
        yield scene
    finally:
        if window is not None and previous is not None:
            window.scene = previous
        for kind, old in before.items():
            coll = getattr(bpy.data, kind)
            for datablock in list(coll):
                if datablock not in old:
                    coll.remove(datablock)
        bpy.data.scenes.remove(scene)


def export_folded_file(
    path: str | Path,
    mesh: FoldMesh,
    frames: np.ndarray | Sequence[np.ndarray],
    *,
    fold_angles: np.ndarray | Sequence[np.ndarray] | None = None,
    frame_numbers: Sequence[int] | None = None,
    name: str = "Folded",
    fps: int = 24,
    **fold_kwargs,
) -> Path:
    """Write the folded ``mesh`` at ``frames`` (``(n, 3)`` or ``(k, n, 3)`` mm) to ``path``; returns the path.

    By suffix: ``.obj``/``.stl`` the last frame; ``.glb``/``.gltf`` the last frame, plus morph targets and an
    animation when there are several frames; ``.blend`` an object with the frames baked to keyed shape keys;
    ``.fold`` the folded FOLD file (``core.fold_format.write_folded_fold``, one FOLD frame per frame, with
    ``fold_angles``); ``.svg`` the flat crease pattern. Raises ``ValueError`` for an unknown suffix.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    arr = _frames_array(frames, mesh.n_vertices)
    if suffix == ".svg":
        write_pattern_svg(path, mesh)
        return path
    if suffix == ".fold":
        from ..core.io import fold as fold_format

        angles = fold_angles
        if angles is None:
            from ..core.metrics import measures as metrics

            angles = [metrics.fold_angles(mesh, p) for p in arr]
        fold_format.write_folded_fold(path, mesh, list(arr), list(np.atleast_2d(angles)), **fold_kwargs)
        return path
    if suffix not in BLENDER_SUFFIXES:
        raise ValueError(f"{path}: cannot export '{suffix}' files; use one of .fold .svg {' '.join(BLENDER_SUFFIXES)}")
    path.parent.mkdir(parents=True, exist_ok=True)
    numbers = list(frame_numbers) if frame_numbers is not None else list(range(1, len(arr) + 1))
    from . import bake, mesh_object

    with temporary_scene() as scene:
        scene.render.fps = int(fps)
        scene.frame_start, scene.frame_end = numbers[0], numbers[-1]
        ob = mesh_object.create_fold_object(mesh, arr[-1], name, scene.collection, scene=scene, creases=False)
        if len(arr) > 1 and suffix in (".glb", ".gltf", ".blend"):
            bake.bake_shape_keys(ob, numbers, list(arr), scene=scene)
            scene.frame_set(numbers[-1])
        _run_exporter(path, suffix, ob, animated=len(arr) > 1)
    return path


def _run_exporter(path: Path, suffix: str, ob: bpy.types.Object, *, animated: bool) -> None:
    # The temporary scene holds only ``ob``; select it so "selected only" exports nothing else.
    ob.select_set(True)
    if suffix == ".obj":
        result = bpy.ops.wm.obj_export(
            filepath=str(path), export_selected_objects=True, export_materials=False, export_uv=False
        )
    elif suffix == ".stl":
        result = bpy.ops.wm.stl_export(filepath=str(path), export_selected_objects=True, ascii_format=False)
    elif suffix in (".glb", ".gltf"):
        result = bpy.ops.export_scene.gltf(
            filepath=str(path),
            export_format="GLB" if suffix == ".glb" else "GLTF_SEPARATE",
            use_selection=True,
            use_active_scene=True,  # otherwise every scene (the user's too) is written
            export_morph=animated,
            export_morph_normal=False,
            export_animations=animated,
            export_apply=False,
        )
    else:  # .blend
        bpy.data.libraries.write(str(path), {ob}, fake_user=True)
        result = {"FINISHED"}
    if "FINISHED" not in result or not path.exists():
        raise OSError(f"{path}: Blender's {suffix} exporter did not write the file ({result})")


def write_pattern_svg(path: str | Path, mesh: FoldMesh, *, stroke_width: float | None = None) -> Path:
    """Write the flat crease pattern of ``mesh`` as SVG in Origami Simulator's convention; returns the path.

    Every drawn stroke (edges with a source polyline; diagonals added by triangulation are left out) becomes a
    ``<polyline>`` per chain of one assignment and angle: stroke black/red/blue/yellow/magenta/green for
    B/M/V/F/U/C, ``opacity`` = |fold angle| / 180 (1 for F and for creases without an angle). Coordinates are
    millimetres with y flipped back to SVG's y-down; ``width``/``height`` carry ``mm`` so plotters and laser
    cutters get the true size. The file is written atomically.
    """
    path = Path(path)
    v = mesh.vertices
    lo, hi = v.min(axis=0), v.max(axis=0)
    w, h = (hi - lo).tolist()
    width = stroke_width if stroke_width is not None else max(w, h) / 300.0
    drawn = mesh.edge_polyline >= 0
    if not drawn.any():
        drawn = mesh.assignments != "F"
    angles = np.where(np.isfinite(mesh.fold_angles), mesh.fold_angles, np.nan)
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.6g}mm" height="{h:.6g}mm" viewBox="0 0 {w:.6g} {h:.6g}">',
        f"<!-- Curved Fold crease pattern: {int(drawn.sum())} segments, Origami Simulator colours, "
        "opacity = |fold angle| / 180 -->",
    ]
    from ..core.pattern.polylines import chain_edges

    for a in SVG_STROKES:
        for poly in np.unique(mesh.edge_polyline[drawn & (mesh.assignments == a)]):
            sel = drawn & (mesh.assignments == a) & (mesh.edge_polyline == poly)
            for angle in np.unique(np.round(np.nan_to_num(angles[sel], nan=999.0), 6)):
                group = sel & (np.round(np.nan_to_num(angles, nan=999.0), 6) == angle)
                opacity = 1.0 if a in "FBC" or angle == 999.0 else min(abs(float(angle)) / 180.0, 1.0)
                for chain in chain_edges(mesh.edges[group]):
                    pts = v[chain] - lo
                    pts[:, 1] = h - pts[:, 1]
                    coords = " ".join(f"{x:.6g},{y:.6g}" for x, y in pts)
                    attrs = f'stroke="{SVG_STROKES[a]}" fill="none" stroke-width="{width:.4g}"'
                    if opacity != 1.0:
                        attrs += f' opacity="{opacity:.6g}"'
                    src = mesh.sources[poly] if 0 <= poly < len(mesh.sources) else ""
                    data = f" data-source={quoteattr(src)}" if src else ""
                    lines.append(f'<polyline {attrs}{data} points="{coords}"/>')
    lines.append("</svg>")
    text = "\n".join(lines) + "\n"
    try:
        from ..core.io.atomic import atomic_write_text

        atomic_write_text(path, text)
    except ImportError:  # core.files is written by another helper; plain write until it exists
        path.write_text(text, encoding="utf-8")
    return path
