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
import math
import tempfile
from collections.abc import Generator, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import bpy
import numpy as np

from ..core import run_to_end
from ..core.io.atomic import atomic_output, atomic_write_text
from ..core.io.gltf import GltfError, check_embedded_gltf, embedded_gltf
from ..core.io.svg import SAMPLED_ATTRIBUTE, SAMPLED_VALUE
from ..core.mesh.fold_mesh import FoldMesh
from .jobs import Job, ObjectHandle, Progress

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


class Scratch:
    """The temporary scene of an export and every datablock made for it, kept from one unit of an export job to the
    next and removed at its end (also on failure or cancel): the user's scene, selection and active object are never
    touched.

    :meth:`unit` runs one unit of work with the temporary scene as the window's (the exporters and the depsgraph
    read the context's scene) and the user's scene back afterwards, before the window redraws, and records what the
    unit made. Only the units' own datablocks are recorded: something the user makes between two slices of the job
    is not removed with the export's (a difference of ``bpy.data`` over the whole job would take it)."""

    KINDS = ("objects", "meshes", "curves", "actions", "materials")

    def __init__(self, name: str = "Curved Fold Export"):
        self.name = name
        self.scene: bpy.types.Scene | None = None
        self.made: dict[str, list] = {kind: [] for kind in self.KINDS}

    @contextlib.contextmanager
    def unit(self) -> Iterator[bpy.types.Scene]:
        """One unit of work in the temporary scene (made by the first unit). Switching the window's scene there and
        back takes ~1.3 ms: a unit of little work that makes nothing (a frame's evaluation) does without."""
        before = {kind: set(getattr(bpy.data, kind)) for kind in self.KINDS}
        window = bpy.context.window
        previous = window.scene if window is not None else None
        try:
            if self.scene is None:
                self.scene = bpy.data.scenes.new(self.name)
            if window is not None:
                window.scene = self.scene
            yield self.scene
        finally:
            if window is not None and previous is not None:
                window.scene = previous
            for kind, old in before.items():
                self.made[kind].extend(d for d in getattr(bpy.data, kind) if d not in old)

    def remove(self) -> None:
        """Remove the temporary scene and everything the units made."""
        for kind in self.KINDS:
            coll = getattr(bpy.data, kind)
            for datablock in self.made[kind]:
                with contextlib.suppress(ReferenceError):  # removed with another (a mesh's shape keys' action)
                    coll.remove(datablock)
            self.made[kind] = []
        if self.scene is not None:
            bpy.data.scenes.remove(self.scene)
            self.scene = None


UNITS = {"m": 1.0, "mm": 1000.0}
"""File length units the mesh exporters offer: file units per metre (Blender units of a unit-scale-1 scene)."""

DEFAULT_UNIT = {".stl": "mm", ".obj": "m", ".glb": "m", ".gltf": "m", ".blend": "m"}
"""STL in millimetres (what slicers assume); glTF must be metres; OBJ keeps Blender's metres unless asked."""


def automatic_unit(path: str | Path, scene: bpy.types.Scene | None) -> str | None:
    """The Export Mesh operator's Automatic unit for ``path``: for OBJ the unit of ``scene``'s Blender units, as
    Blender's own OBJ exporter writes them and its importer reads them back (millimetres in a scene of 1 unit = 1
    mm: in metres the model came back 1,000× too small there; a designer session); else None
    (:data:`DEFAULT_UNIT`)."""
    if Path(path).suffix.lower() != ".obj" or scene is None:
        return None
    from . import mesh_object

    return "mm" if math.isclose(mesh_object.mm_per_unit(scene), 1.0, rel_tol=1e-6) else None


PAPER_RGBA = (0.93, 0.91, 0.86, 1.0)
"""Base colour of the exported paper material (an off-white sheet)."""


def flat_uv(mesh: FoldMesh) -> np.ndarray:
    """Per-vertex texture coordinates from the flat crease pattern: shifted to the lower-left corner and divided by
    the larger extent (Origami Simulator's OBJ convention), so an image printed on the sheet follows the fold and
    keeps its aspect ratio. Shape ``(n, 2)``, in [0, 1]."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    lo = v.min(axis=0)
    extent = float(np.ptp(v, axis=0).max()) or 1.0
    return (v - lo) / extent


def _paper_surface(ob: bpy.types.Object, mesh: FoldMesh) -> None:
    """Give the export object UVs from the flat pattern and a double-sided paper material (glTF's default material
    is single-sided: flaps seen from below would vanish)."""
    me = ob.data
    loops = np.empty(len(me.loops), dtype=np.int64)
    me.loops.foreach_get("vertex_index", loops)
    uv = me.uv_layers.new(name="UVMap")
    uv.data.foreach_set("uv", flat_uv(mesh)[loops].astype(np.float32).ravel())
    mat = bpy.data.materials.new("Paper")
    if mat.node_tree is None:  # Blender 4.x; 5.x materials always have nodes
        mat.use_nodes = True
    mat.use_backface_culling = False
    mat.diffuse_color = PAPER_RGBA
    bsdf = next((n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled"), None)
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = PAPER_RGBA
        bsdf.inputs["Roughness"].default_value = 0.9
    me.materials.append(mat)


def _copy_modifiers(source: bpy.types.Object, target: bpy.types.Object, length_factor: float = 1.0) -> None:
    """Copy ``source``'s enabled modifiers (Solidify for thickness, ...) with their settings onto ``target``;
    lengths (properties with unit LENGTH: a thickness, an offset) times ``length_factor``, the ratio of the source
    scene's Blender unit to the export scene's. The export scene has unit scale 1 (metres): a Solidify of 0.5 in a
    scene of 1 unit = 1 mm was copied as 0.5 m, and the exported model came out ~1000× too thick."""
    for mod in source.modifiers:
        if not (mod.show_viewport or mod.show_render):
            continue
        new = target.modifiers.new(mod.name, mod.type)
        for prop in mod.bl_rna.properties:
            key = prop.identifier
            if prop.is_readonly or key in ("name", "type", "rna_type"):
                continue
            with contextlib.suppress(AttributeError, TypeError, ValueError):
                value = getattr(mod, key)
                if prop.type == "FLOAT" and getattr(prop, "unit", "NONE") == "LENGTH" and length_factor != 1.0:
                    value = value * length_factor if prop.array_length == 0 else [v * length_factor for v in value]
                setattr(new, key, value)
        if mod.type == "NODES":  # Geometry Nodes inputs live in ID properties
            for key in mod.keys():
                with contextlib.suppress(AttributeError, TypeError, ValueError, KeyError):
                    new[key] = mod[key]


def _evaluated_positions(
    ob: bpy.types.Object, positions_mm: np.ndarray, scale: float, depsgraph: bpy.types.Depsgraph
) -> tuple[object, np.ndarray]:
    """Put ``positions_mm`` on ``ob``'s mesh and return its evaluated object (modifiers applied) and positions (mm)
    in ``depsgraph`` (the export scene's)."""
    me = ob.data
    me.attributes["position"].data.foreach_set("vector", (positions_mm / scale).astype(np.float32).ravel())
    me.update()
    depsgraph.update()
    ev = ob.evaluated_get(depsgraph)
    co = np.empty(3 * len(ev.data.vertices), dtype=np.float32)
    ev.data.attributes["position"].data.foreach_get("vector", co)
    return ev, co.reshape(-1, 3).astype(np.float64) * scale


def _bake_evaluated_steps(
    ob: bpy.types.Object, mesh: FoldMesh, scratch: Scratch, numbers: list[int], frames: np.ndarray
) -> Generator[Progress, None, bpy.types.Object]:
    """A new object holding ``ob``'s evaluated mesh (modifiers applied) with every frame baked to shape keys from
    the evaluated positions, basis = the evaluated flat sheet; one frame's evaluation per unit. Raises ValueError if
    a modifier changes the topology from frame to frame."""
    from . import bake, mesh_object

    with scratch.unit() as scene:
        scale = mesh_object.mm_per_unit(scene)
        depsgraph = scene.view_layers[0].depsgraph  # the context's while the window shows the export scene
        ev, base = _evaluated_positions(ob, mesh.vertices_3d, scale, depsgraph)
        out = bpy.data.meshes.new_from_object(ev, preserve_all_data_layers=True, depsgraph=depsgraph)
    shapes = []
    for k, p in enumerate(frames):
        yield _progress("setup", k + 1, len(frames))
        shapes.append(_evaluated_positions(ob, p, scale, depsgraph)[1])
    yield _progress("setup", len(frames), len(frames))
    with scratch.unit() as scene:
        baked = bpy.data.objects.new(ob.name, out)
        scene.collection.objects.link(baked)
        scene.collection.objects.unlink(ob)
        bake.bake_shape_keys(baked, numbers, shapes, basis=base, scene=scene)
    return baked


def _progress(stage: str, k: int = 0, n: int = 0) -> Progress:
    """Progress of the file-writing half of an export (from 50 %: the export job reads the frames first)."""
    return Progress(stage, frame=k, n_frames=n, fraction=0.5 + 0.45 * (k / n if n else 1.0), alone=stage == "export")


def export_folded_file(
    path: str | Path,
    mesh: FoldMesh,
    frames: np.ndarray | Sequence[np.ndarray],
    **kwargs,
) -> Path:
    """Write the folded ``mesh`` at ``frames`` to ``path`` in one call (the command line, scripts); returns the path.
    The arguments and what is written are :func:`export_steps`'."""
    return run_to_end(export_steps(path, mesh, frames, **kwargs))


def export_steps(
    path: str | Path,
    mesh: FoldMesh,
    frames: np.ndarray | Sequence[np.ndarray],
    *,
    fold_angles: np.ndarray | Sequence[np.ndarray] | None = None,
    frame_numbers: Sequence[int] | None = None,
    name: str = "Folded",
    fps: int = 24,
    unit: str | None = None,
    modifiers_from: bpy.types.Object | None = None,
    scratch: Scratch | None = None,
    **fold_kwargs,
) -> Generator[Progress, None, Path]:
    """Write the folded ``mesh`` at ``frames`` (``(n, 3)`` or ``(k, n, 3)`` mm) to ``path`` in units of work (one
    ``next`` each, yielding the :class:`~.jobs.Progress` of the unit that follows); returns the path.

    By suffix: ``.obj``/``.stl`` the last frame; ``.glb``/``.gltf`` the last frame, plus morph targets (with morph
    normals) and an animation when there are several frames, the flat sheet as the base shape; ``.blend`` an object
    with the frames baked to keyed shape keys; ``.fold`` the folded FOLD file (``core.io.fold.write_folded_fold``,
    one FOLD frame per frame, with ``fold_angles``); ``.svg`` the flat crease pattern. Meshes carry UVs from the flat
    pattern (:func:`flat_uv`) and a double-sided paper material. ``unit`` is ``"mm"`` or ``"m"`` for STL/OBJ
    (default :data:`DEFAULT_UNIT`), any FOLD ``frame_unit`` for ``.fold``. ``modifiers_from`` is an object whose
    enabled modifiers (Solidify, ...) are applied to the exported mesh at every frame. Raises ``ValueError`` for an
    unknown suffix or unit.

    Units: FOLD encodes a frame per unit and writes the file in the last; the Blender formats set up the temporary
    scene (:class:`Scratch`, given as ``scratch`` by a job that must know it) in units (one per frame when a
    modifier is evaluated), then call Blender's exporter in one unit of its own (``alone``), which cannot be split:
    ~200 ms for a glTF of 3,000 faces with 60 morph targets (docs/benchmarks.md). The file is written atomically in
    the last unit: closed before it (a cancelled job), the generator leaves no file and the temporary scene removed.
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

            angles = []
            for k, p in enumerate(arr):
                angles.append(metrics.fold_angles(mesh, p))
                yield _progress("frame", k + 1, len(arr))
        if unit is not None:
            fold_kwargs["unit"] = unit  # FOLD has its own units (frame_unit)
        yield _progress("encode", 0, len(arr))  # the key frame (the flat pattern), then a frame per unit
        encode = fold_format.folded_fold_text_steps(mesh, list(arr), list(np.atleast_2d(angles)), **fold_kwargs)
        while True:
            try:
                k = next(encode)
            except StopIteration as done:
                text = done.value
                break
            yield _progress("encode", k + 1, len(arr))
        yield _progress("write", len(arr), len(arr))
        atomic_write_text(path, text)
        return path
    if suffix not in BLENDER_SUFFIXES:
        raise ValueError(f"{path}: cannot export '{suffix}' files; use one of .fold .svg {' '.join(BLENDER_SUFFIXES)}")
    unit = unit or DEFAULT_UNIT[suffix]
    if unit not in UNITS or (unit != "m" and suffix not in (".stl", ".obj")):
        raise ValueError(f"{path}: unit {unit!r} not offered for '{suffix}' (STL/OBJ: mm or m; others: m)")
    numbers = list(frame_numbers) if frame_numbers is not None else list(range(1, len(arr) + 1))
    animated = len(arr) > 1 and suffix in (".glb", ".gltf", ".blend")
    from . import bake, mesh_object

    scratch = scratch if scratch is not None else Scratch()
    yield _progress("setup", 0, len(arr))
    try:
        with scratch.unit() as scene:
            scene.render.fps = int(fps)
            scene.frame_start, scene.frame_end = numbers[0], numbers[-1]
            # Animated: the mesh itself is the flat sheet (= the basis key), so the base normals belong to the base
            # positions; morph targets then carry their own normals.
            base = mesh.vertices_3d if animated else arr[-1]
            ob = mesh_object.create_fold_object(mesh, base, name, scene.collection, scene=scene, creases=False)
            _paper_surface(ob, mesh)
            if modifiers_from is not None:
                user_scene = next(iter(modifiers_from.users_scene), None)
                factor = (
                    1.0 if user_scene is None else mesh_object.mm_per_unit(user_scene) / mesh_object.mm_per_unit(scene)
                )
                _copy_modifiers(modifiers_from, ob, factor)
        if animated and len(ob.modifiers):
            ob = yield from _bake_evaluated_steps(ob, mesh, scratch, numbers, arr)
        elif animated:
            yield _progress("setup", len(arr), len(arr))
            with scratch.unit() as scene:
                bake.bake_shape_keys(ob, numbers, list(arr), scene=scene)
        with scratch.unit() as scene:
            if modifiers_from is not None:  # turned and scaled as in the user's scene (not moved: at the origin)
                ob.matrix_world = modifiers_from.matrix_world.to_3x3().to_4x4()
            if animated:
                scene.frame_set(numbers[0])
        yield _progress("export")
        with scratch.unit() as scene, _exported_as(ob, name):
            path.parent.mkdir(parents=True, exist_ok=True)
            with atomic_output(path) as tmp:
                scale = UNITS[unit] * mesh_object.mm_per_unit(scene) / 1000.0
                _run_exporter(tmp, suffix, ob, animated=animated, scale=scale)
                check_complete(tmp, suffix, _exported_vertex_count(ob, scene))
    finally:
        scratch.remove()
    return path


@dataclass
class ExportResult:
    """What an export job wrote: the file, how many frames, whether they were baked frames."""

    path: Path
    n_frames: int
    baked: bool


class ExportWatch:
    """What an export job shows :mod:`.jobs` in place of a preview: nothing is shown (:meth:`show` and
    :meth:`restore` do nothing), the folded object it reads is watched for Edit Mode (its arrays are empty there:
    the job stops with the jobs' one-line message), and a save cancels the job while it holds its temporary scene
    (:attr:`holds_datablocks`), which the file would otherwise keep."""

    def __init__(self, handle: ObjectHandle, scratch: Scratch):
        self.handle = handle
        self.scratch = scratch

    @property
    def holds_datablocks(self) -> bool:
        return self.scratch.scene is not None

    def edited(self) -> bpy.types.Object | None:
        return self.handle.get()

    def show(self, positions_mm: np.ndarray) -> None:
        pass

    def restore(self) -> None:
        pass


def baked_positions(ob: bpy.types.Object, frame: int, scale: float) -> np.ndarray:
    """Positions (mm) of ``ob``'s baked ``frame`` (its shape key; ``scale`` mm per Blender unit)."""
    from . import bake

    co = np.empty(3 * len(ob.data.vertices), dtype=np.float32)
    ob.data.shape_keys.key_blocks[bake.key_name(frame)].points.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64) * scale


def current_positions(ob: bpy.types.Object, scale: float) -> np.ndarray:
    """Positions (mm) of ``ob``'s vertices (its mesh, without shape keys or modifiers)."""
    co = np.empty(3 * len(ob.data.vertices), dtype=np.float32)
    ob.data.attributes["position"].data.foreach_get("vector", co)
    return co.reshape(-1, 3).astype(np.float64) * scale


def current_frame_positions(ob: bpy.types.Object, depsgraph: bpy.types.Depsgraph, scale: float) -> np.ndarray:
    """Positions (mm) of ``ob``'s own vertices at the current frame: the shape-key mix (animated values, from
    ``depsgraph``) without the modifiers, which the export applies itself (``export_steps(modifiers_from=ob)``)."""
    me = ob.data
    n = len(me.vertices)
    co = np.empty(3 * n, dtype=np.float32)
    me.attributes["position"].data.foreach_get("vector", co)
    out = co.reshape(-1, 3).astype(np.float64)
    keys = me.shape_keys
    if keys is not None and keys.use_relative and len(keys.key_blocks) > 1:
        evaluated = keys.evaluated_get(depsgraph)

        def key_co(kb) -> np.ndarray:
            buf = np.empty(3 * n, dtype=np.float32)
            kb.points.foreach_get("co", buf)
            return buf.reshape(-1, 3).astype(np.float64)

        out = key_co(keys.reference_key)
        for kb, ev in zip(keys.key_blocks[1:], evaluated.key_blocks[1:], strict=True):
            if not kb.mute and ev.value != 0.0:
                out += ev.value * (key_co(kb) - key_co(kb.relative_key))
    return out * scale


def export_job(
    ob: bpy.types.Object, path: str | Path, *, unit: str | None = None, scene: bpy.types.Scene | None = None
) -> Job:
    """The Export Folded Mesh operator's one scene call: a job writing the folded object ``ob`` to ``path`` (the
    format by its suffix; ``unit`` for STL/OBJ) whose result is an :class:`ExportResult`.

    Units: the flat pattern read back from the object; one frame read per unit (the baked frames' shape keys, or
    the current frame; for FOLD with its unwrapped fold angles, ``core.metrics.measures.AngleFollower``); then
    :func:`export_steps`' units. Blender's exporter is one unit that cannot be split. Cancelled before its last
    unit, the job leaves no file (an existing one untouched) and no temporary datablock."""
    from . import bake, mesh_object, timeline

    timeline.finish_frame_job(ob)  # the frame the timeline is on, not the previous one a cancel would restore

    scene = scene if scene is not None else bpy.context.scene
    handle = ObjectHandle(ob)
    path = Path(path)
    suffix = path.suffix.lower()
    fps = scene.render.fps
    scratch = Scratch()

    def steps():
        ob = handle.require("folded object")
        mesh = mesh_object.read_fold_mesh(ob)
        frames = bake.baked_frames(ob)
        scale = mesh_object.mm_per_unit(scene)
        current = suffix in (".obj", ".stl")  # the current frame, with the shape keys' animated values
        n = 1 if current or not frames else len(frames)
        follow = None
        if suffix == ".fold":
            from ..core.metrics import measures as metrics

            # the solver's unwrapped angles of the last fold start an unbaked frame (a valley past flat is 199°,
            # not −161°); baked frames are followed from the flat sheet
            follow = metrics.AngleFollower(mesh, None if frames else mesh_object.simulated_fold_angles(ob))
        positions, angles = [], []
        for k in range(n):
            yield Progress("frame", frame=k + 1, n_frames=n, fraction=0.5 * k / n)
            ob = handle.require("folded object")
            if current:
                p = current_frame_positions(ob, bpy.context.evaluated_depsgraph_get(), scale)
            else:
                p = baked_positions(ob, frames[k], scale) if frames else current_positions(ob, scale)
            positions.append(p)
            if follow is not None:
                angles.append(follow(p))
        if follow is not None:
            kwargs = {"fold_angles": angles}
        else:
            kwargs = {"name": ob.name, "fps": fps, "modifiers_from": ob, "unit": unit, "scratch": scratch}
            if not current:
                kwargs["frame_numbers"] = frames or None
        written = yield from export_steps(path, mesh, positions, **kwargs)
        return ExportResult(written, len(positions), bool(frames))

    return Job(ob.name, "exporting", steps(), ExportWatch(handle, scratch))


def check_complete(path: Path, suffix: str, n_vertices: int) -> None:
    """Raise :class:`OSError` unless the file a Blender exporter wrote at ``path`` is whole.

    Blender's C++ OBJ writer ignores write errors (a full disk left an OBJ cut mid-line and the operator said
    "File exported successfully"), so the file is checked before it replaces anything: an OBJ must end with a
    newline and hold ``n_vertices`` ``v`` lines; a GLB's header length must equal the file size; a .gltf must be
    whole JSON whose embedded buffers hold the bytes they say; a .blend file must end with its ``ENDB`` block.
    """
    suffix = suffix.lower()
    size = path.stat().st_size
    if suffix == ".obj":
        with open(path, "rb") as fh:
            data = fh.read()
        count = data.count(b"\nv ") + data.startswith(b"v ")
        # Blender writes the elements (f, l) last: a file cut on a line boundary after the vertices (bpy 5.2's
        # writer puts all v lines in the first half) must not pass
        last = data.rstrip(b"\n").rsplit(b"\n", 1)[-1]
        if not data.endswith(b"\n") or count != n_vertices or not last.startswith((b"f ", b"l ")):
            raise OSError(f"the OBJ file is incomplete ({count} of {n_vertices} vertices, {size} bytes written)")
    elif suffix == ".glb":
        with open(path, "rb") as fh:
            head = fh.read(12)
        declared = int.from_bytes(head[8:12], "little") if len(head) == 12 and head[:4] == b"glTF" else -1
        if declared != size:
            raise OSError(f"the GLB file is incomplete ({size} of {declared} bytes written)")
    elif suffix == ".stl":
        with open(path, "rb") as fh:
            head = fh.read(84)
        if len(head) == 84 and not head.startswith(b"solid"):
            expected = 84 + 50 * int.from_bytes(head[80:84], "little")
            if expected != size:  # a writer cut short can leave a header that counts no triangles yet
                raise OSError(
                    f"the STL file is incomplete ({size} bytes written, its header counts "
                    f"{int.from_bytes(head[80:84], 'little')} triangles: {expected} bytes)"
                )
    elif suffix == ".gltf":
        try:
            check_embedded_gltf(path.read_text(encoding="utf-8"))
        except (GltfError, UnicodeDecodeError) as exc:
            raise OSError(f"the glTF file is incomplete: {exc}") from None
    elif suffix == ".blend":
        with open(path, "rb") as fh:
            fh.seek(max(size - 64, 0))
            tail = fh.read()
        if b"ENDB" not in tail:
            raise OSError(f"the .blend file is incomplete (no end block; {size} bytes written)")


def _exported_vertex_count(ob: bpy.types.Object, scene: bpy.types.Scene) -> int:
    """Vertices the exporter writes for ``ob``: those of the evaluated mesh (modifiers applied, e.g. Solidify)."""
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    return len(ob.evaluated_get(depsgraph).data.vertices)


@contextlib.contextmanager
def _exported_as(ob: bpy.types.Object, name: str) -> Iterator[None]:
    """Give the temporary export copy ``ob`` the exact ``name`` (the user's object's, which holds it, so the copy
    was called ``name.001``) while the exporter runs, so exported nodes carry the object's own name; the user's
    object gets its name back afterwards, whatever happens."""
    holder = bpy.data.objects.get(name) if ob.name != name else None
    if holder is None:
        yield
        return
    holder.rename(name + ".curved-fold-export", mode="ALWAYS")
    ob.rename(name, mode="ALWAYS")
    try:
        yield
    finally:
        ob.rename(name + ".curved-fold-copy", mode="ALWAYS")
        holder.rename(name, mode="ALWAYS")


def _run_exporter(path: Path, suffix: str, ob: bpy.types.Object, *, animated: bool, scale: float = 1.0) -> None:
    # The temporary scene holds only ``ob``; select it so "selected only" exports nothing else.
    ob.select_set(True)
    if suffix == ".obj":
        result = bpy.ops.wm.obj_export(
            filepath=str(path),
            export_selected_objects=True,
            export_materials=False,
            export_uv=True,
            export_normals=True,
            apply_modifiers=True,
            global_scale=scale,
        )
    elif suffix == ".stl":
        result = bpy.ops.wm.stl_export(
            filepath=str(path),
            export_selected_objects=True,
            ascii_format=False,
            apply_modifiers=True,
            global_scale=scale,
        )
    elif suffix == ".gltf":  # one self-contained file: the GLB with its binary chunk embedded (core.io.gltf)
        with tempfile.TemporaryDirectory(prefix="curved-fold-gltf-") as folder:
            glb = Path(folder) / "export.glb"
            _export_glb(glb, ob, animated)
            try:
                text = embedded_gltf(glb.read_bytes() if glb.exists() else b"")
            except GltfError as exc:
                raise OSError(f"Blender's glTF exporter did not write a whole file: {exc}") from None
        path.write_text(text, encoding="utf-8")
        return
    elif suffix == ".glb":
        result = _export_glb(path, ob, animated)
    else:  # .blend
        # with its scene, so the file opens showing the object and the baked frame range (an object alone opened
        # to an empty scene, "Library file, loading empty scene", reachable only through Append)
        bpy.data.libraries.write(str(path), {ob.users_scene[0], ob}, fake_user=True)
        result = {"FINISHED"}
    if "FINISHED" not in result or not path.exists():
        raise OSError(f"{path}: Blender's {suffix} exporter did not write the file ({result})")


def _without_own_attributes(ob: bpy.types.Object) -> None:
    """Remove the add-on's ``cf_*`` attributes from the temporary export copy ``ob``: no exporter writes them, and the
    NaN fold angles of border edges made bpy 5.2's glTF exporter, which validates every mesh, print "Mesh Folded is
    not valid, and may be exported wrongly" on every export."""
    attributes = ob.data.attributes
    for name in [a.name for a in attributes if a.name.startswith("cf_")]:
        attributes.remove(attributes[name])


def _export_glb(path: Path, ob: bpy.types.Object, animated: bool) -> set[str]:
    """Blender's glTF exporter writing ``ob``, the selected object of the active (temporary) scene, to ``path`` as
    GLB (without the add-on's attributes)."""
    _without_own_attributes(ob)
    return bpy.ops.export_scene.gltf(
        filepath=str(path),
        export_format="GLB",
        use_selection=True,
        use_active_scene=True,  # otherwise every scene (the user's too) is written
        export_morph=animated,
        export_morph_normal=animated,
        export_animations=animated,
        export_apply=not animated,  # animated: modifiers were already baked into the shape keys
        export_texcoords=True,
        export_normals=True,
        export_materials="EXPORT",
    )


SVG_LAYOUTS = ("origami-simulator", "cutter")
"""``origami-simulator``: every role, opacity = fold angle (reads back into Origami Simulator and Curved Fold).
``cutter``: two layers for a laser cutter or plotter, ``cut`` (borders and cuts, hairline) and ``score`` (mountains,
valleys, undriven hinges, a heavier line), no facets and no opacity; colours stay Origami Simulator's."""

CUT_ROLES, SCORE_ROLES = ("B", "C"), ("M", "V", "U")


def _svg_number(x: float) -> str:
    """The shortest decimal that reads back as the same double (``repr``), without a trailing ``.0``: a crease
    pattern read back from our SVG is the one we wrote, to the last bit. Six significant digits moved vertices by up
    to 1e-3 mm on a 144 mm sheet, and a pattern whose fold passes near a branching of equilibria (Rotating_Star)
    then folded into another state (52 iterations and warp up to 56° instead of 24 and 31°)."""
    text = repr(float(x) + 0.0)  # + 0.0: no "-0"
    return text[:-2] if text.endswith(".0") else text


def write_pattern_svg(
    path: str | Path,
    mesh: FoldMesh,
    *,
    stroke_width: float | None = None,
    layout: str = "origami-simulator",
    cut_width: float = 0.025,
    score_width: float = 0.2,
) -> Path:
    """Write the flat crease pattern of ``mesh`` as SVG in Origami Simulator's convention; returns the path.

    Every drawn stroke (edges with a source polyline; diagonals added by triangulation are left out) becomes a
    ``<polyline>`` per chain of one assignment and angle: stroke black/red/blue/yellow/magenta/green for
    B/M/V/F/U/C, ``opacity`` = |fold angle| / 180 (1 for F and for creases without an angle). Cuts, which the mesh
    stores as split border edges, are recognised and drawn once in green. Coordinates are millimetres with y
    flipped back to SVG's y-down; ``width``/``height`` carry ``mm`` so plotters and laser cutters get the true
    size. ``layout="cutter"`` (:data:`SVG_LAYOUTS`) groups the strokes into ``cut`` and ``score`` layers with
    ``cut_width``/``score_width`` (mm) line weights. The file is written atomically.
    """
    if layout not in SVG_LAYOUTS:
        raise ValueError(f"SVG layout {layout!r}: expected one of {', '.join(SVG_LAYOUTS)}")
    cutter = layout == "cutter"
    path = Path(path)
    v = mesh.vertices
    lo, hi = v.min(axis=0), v.max(axis=0)
    w, h = (hi - lo).tolist()
    width = stroke_width if stroke_width is not None else max(w, h) / 300.0
    drawn = mesh.edge_polyline >= 0
    if not drawn.any():
        drawn = mesh.assignments != "F"
    # The mesh stores a cut as border edges (split along the slit): give them back the Cut role, and draw each
    # slit once by merging coincident vertices (a vertex index per position) and dropping repeated segments.
    from ..core.io.fold import cut_mask

    assignments = mesh.assignments.copy()
    assignments[cut_mask(v, mesh.edges, assignments, mesh.triangles)] = "C"
    size = float(np.ptp(v, axis=0).max()) or 1.0
    _, first, inverse = np.unique(np.round(v / (1e-9 * size)), axis=0, return_index=True, return_inverse=True)
    edges = np.sort(first[inverse.reshape(-1)][mesh.edges], axis=1)
    once = np.zeros(len(edges), dtype=bool)
    once[np.unique(edges, axis=0, return_index=True)[1]] = True
    drawn &= once
    angles = np.where(np.isfinite(mesh.fold_angles), mesh.fold_angles, np.nan)
    if cutter:
        drawn &= np.isin(assignments, CUT_ROLES + SCORE_ROLES)
    ns = ' xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"' if cutter else ""
    head = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg"{ns} width="{w:.6g}mm" height="{h:.6g}mm" '
        f'viewBox="0 0 {w:.6g} {h:.6g}">',
        f"<!-- Curved Fold crease pattern: {int(drawn.sum())} segments, Origami Simulator colours, "
        + ("cut and score layers -->" if cutter else "opacity = |fold angle| / 180 -->"),
    ]
    by_role: dict[str, list[str]] = {a: [] for a in SVG_STROKES}
    from ..core.pattern.polylines import chain_edges

    angle_key = np.round(np.nan_to_num(angles, nan=999.0), 6)
    for a in SVG_STROKES:
        lines = by_role[a]
        if cutter:
            width = cut_width if a in CUT_ROLES else score_width
        # the role's edges grouped by source stroke and angle, in that order, each group in edge order (one sort:
        # masks over every edge per stroke took ~0.2 s on a 3,200-stroke pattern)
        idx = np.flatnonzero(drawn & (assignments == a))
        if len(idx) == 0:
            continue
        idx = idx[np.lexsort((angle_key[idx], mesh.edge_polyline[idx]))]
        poly_of, angle_of = mesh.edge_polyline[idx], angle_key[idx]
        starts = np.flatnonzero(np.r_[True, (poly_of[1:] != poly_of[:-1]) | (angle_of[1:] != angle_of[:-1])])
        for group in np.split(idx, starts[1:]):
            poly, angle = int(mesh.edge_polyline[group[0]]), float(angle_key[group[0]])
            opacity = 1.0 if a in "FBC" or angle == 999.0 else min(abs(angle) / 180.0, 1.0)
            for chain in chain_edges(edges[group]):
                pts = v[chain] - lo
                pts[:, 1] = h - pts[:, 1]
                coords = " ".join(f"{_svg_number(x)},{_svg_number(y)}" for x, y in pts.tolist())
                attrs = f'stroke="{SVG_STROKES[a]}" fill="none" stroke-width="{width:.4g}"'
                if opacity != 1.0 and not cutter:
                    attrs += f' opacity="{_svg_number(opacity)}"'
                src = mesh.sources[poly] if 0 <= poly < len(mesh.sources) else ""
                data = f" data-source={quoteattr(src)}" if src else ""
                data += f' {SAMPLED_ATTRIBUTE}="{SAMPLED_VALUE}"'  # our vertices: read back as written
                lines.append(f'<polyline {attrs}{data} points="{coords}"/>')
    if cutter:
        body = []
        for layer, roles in (("cut", CUT_ROLES), ("score", SCORE_ROLES)):
            body.append(f'<g id="{layer}" inkscape:groupmode="layer" inkscape:label="{layer}">')
            body += [ln for a in roles for ln in by_role[a]]
            body.append("</g>")
    else:
        body = [ln for a in SVG_STROKES for ln in by_role[a]]
    text = "\n".join([*head, *body, "</svg>"]) + "\n"
    atomic_write_text(path, text)
    return path
