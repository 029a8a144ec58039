"""Import a crease pattern file (SVG, FOLD) as a handful of editable curve objects with their crease roles set.

SVG strokes keep their exact geometry (lines, cubics, arcs) from ``core.io.svg.read_svg``; a FOLD file holds straight
segments only, so its edges are chained into polylines (``core.pattern.polylines``). The objects are made by
``scene.curves.objects_from_curves``: one object per role and fold angle, one spline per chain of strokes joined end
to end, and the exact strokes stored on each object (``scene.exact_curves``) so that folding the imported, unedited
curves gives the same mesh as the command line does for the file. They go into a new collection named after the
file. Nothing is written to the scene until the whole file has been read and converted; on failure whatever was
created is removed.

The reading and converting run in units of work (:func:`import_steps`), so the Import operator runs them as a job in
slices with progress and Esc (:func:`import_job`; a 3,200-line SVG took ~190 ms in one call); only the job's commit
writes to the scene.
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from pathlib import Path

import bpy

from ..core import as_units, run_to_end
from ..core.io.reader import read_curves_steps
from ..core.pattern.model import PatternError
from . import jobs

SUFFIXES = (".svg", ".fold")
"""The files the Import operator reads (``core.io.reader.read_curves`` also reads .blend, which Blender opens
itself)."""

Imported = tuple[list[bpy.types.Object], list[str]]


def import_crease_pattern(
    path: str | Path,
    *,
    scene: bpy.types.Scene | None = None,
    collection: bpy.types.Collection | None = None,
) -> Imported:
    """Import ``path`` as curve objects in a new collection (child of ``collection`` or the scene's); return
    ``(objects, warnings)``. The scene is unchanged if reading or conversion fails."""
    commit = run_to_end(import_steps(path, scene=scene, collection=collection))
    return commit()


def import_steps(
    path: str | Path,
    *,
    scene: bpy.types.Scene | None = None,
    collection: bpy.types.Collection | None = None,
) -> Generator[str, None, Callable[[], Imported]]:
    """:func:`import_crease_pattern` in units of work: reading the file and working out its curve objects touch
    nothing; the returned commit makes them (and is all that writes to the scene)."""
    scene = scene or bpy.context.scene
    pattern, segments = None, False
    if Path(path).suffix.lower() == ".fold":  # keep the file's pattern: the command line folds it as it is
        from ..core.io.fold import another_tools_segments, fold_to_pattern, is_our_pattern, read_fold
        from ..core.pattern.discretize import segments_at_interval
        from ..core.pattern.polylines import curves_from_pattern

        if not Path(path).is_file():
            raise PatternError(f"{path}: no such file")
        doc = read_fold(path)
        yield "read"
        if is_our_pattern(doc):
            pattern = shown = fold_to_pattern(doc)
        else:  # another tool's segments, kept unsampled: a fold samples them at its own interval (stored_pattern)
            pattern, segments = another_tools_segments(doc), True
            shown = segments_at_interval(pattern)
        yield "read"
        curves, warnings = curves_from_pattern(shown), list(shown.warnings)
    else:
        curves, warnings = yield from read_curves_steps(path)
    if not curves:
        raise PatternError(f"{path}: no crease lines found")
    yield "read"
    from .curves import chain_steps

    chained = yield from chain_steps(curves)
    parent = collection or scene.collection

    def commit() -> Imported:
        from .mesh_object import mm_per_unit

        coll = bpy.data.collections.new(Path(path).stem)
        before = set(bpy.data.objects), set(bpy.data.curves), set(bpy.data.materials)
        try:
            parent.children.link(coll)
            objects = _objects_from_curves(
                curves, coll, 1.0 / mm_per_unit(scene), Path(path).name, pattern, segments, chained
            )
        except Exception:
            for ob in set(bpy.data.objects) - before[0]:
                bpy.data.objects.remove(ob)
            for cu in set(bpy.data.curves) - before[1]:
                bpy.data.curves.remove(cu)
            for mat in set(bpy.data.materials) - before[2]:
                bpy.data.materials.remove(mat)
            bpy.data.collections.remove(coll)
            raise
        return objects, warnings

    return commit


def import_job(paths: list[str], *, scene: bpy.types.Scene | None = None) -> jobs.Job:
    """The Import operator's job: read ``paths`` one after another in slices, then make every file's curve objects
    in its commit, which returns ``(path, objects, warnings)`` per file read and the first error met (a file that
    fails is reported, and the files read before it are still imported, as before)."""
    from .folding import engine_errors

    scene = scene or bpy.context.scene

    def steps():
        commits: list[tuple[str, Callable[[], Imported]]] = []
        error: BaseException | None = None
        for path in paths:
            try:
                commit = yield from as_units(import_steps(path, scene=scene), jobs.Progress("read"))
            except (*engine_errors(), OSError) as exc:
                error = exc
                break
            commits.append((path, commit))

        def commit_all():
            done = []
            for path, commit in commits:
                objects, warnings = commit()
                done.append((path, objects, warnings))
            return done, error

        return commit_all

    owner = "import " + ", ".join(Path(p).name for p in paths)
    return jobs.Job(owner, "importing", steps())


def _objects_from_curves(curves, coll, unit_scale, name, pattern, segments, chained):
    from .curves import objects_from_curves

    return objects_from_curves(
        curves, coll, unit_scale, import_name=name, pattern=pattern, segments=segments, chained=chained
    )
