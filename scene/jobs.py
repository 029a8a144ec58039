"""Cancellable jobs: Fold, Re-fold, Live re-fold and Bake as generators of short slices of work.

A job wraps a Python generator that does one unit of work per ``next`` (a mesh generation, a Newton iteration, a
chunk of explicit steps, a frame) and yields a :class:`Progress`; when it is exhausted it *returns* a ``commit``
callable that writes the result to the scene and returns what it wrote. So:

* :func:`run_slice` advances a job for about ``budget_ms`` (at least one unit), shows the last positions reached in
  the viewport (the sheet folds while the solver iterates) and, when the generator is done, commits;
* :func:`cancel` closes the generator and restores what the preview changed, byte for byte (a snapshot taken when
  the job started); nothing else was written, because only ``commit`` writes;
* :func:`run_to_end` is the blocking path (``EXEC_DEFAULT``, scripts, ``blender -b``): the same slices, no budget.

One job per folded object (:func:`start`): a live job is superseded by any new job on its object; any other
running job makes a second one fail with :class:`JobBusyError` (one clear line for the user).

Previews: :class:`PositionsPreview` moves an existing fold object's vertices (and its red/blue crease curves);
:class:`MeshPreview` shows a new mesh (a fresh fold, or a rebuilt pattern) in a temporary datablock that is removed
again. The modal operators (``operators/job_modal.py``) call :func:`run_slice` on a timer; the tests call it directly
(timers and modal loops do not run headless).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Generator
from dataclasses import dataclass
from typing import Any

import bpy
import numpy as np

from . import mesh_object

SLICE_MS = 80.0
"""Work per timer tick of a modal job (ms). A slice ends when the next unit, expected to take as long as the longest of
its kind so far (as the last, for the first of a kind), would end past it: slices stay within it unless one unit
alone is longer (running until the budget had passed made slices of the budget plus one unit, 120–180 ms on a
3,000-face bake)."""


class JobBusyError(RuntimeError):
    """A job is already running on this folded object (one job per object)."""


class ObjectHandle:
    """An object a job works on, found again if it is renamed while the job runs: by name, else by its
    ``session_uid`` (kept across renames and undo). A bake of a big pattern takes seconds, and renaming the folded
    mesh in the Outliner meanwhile made every later lookup by name fail (a KeyError out of the modal operator,
    the bake lost)."""

    def __init__(self, ob: bpy.types.Object):
        self.name, self.uid = ob.name, ob.session_uid

    def get(self) -> bpy.types.Object | None:
        """The object, or ``None`` if it was deleted."""
        ob = bpy.data.objects.get(self.name)
        if ob is None or ob.session_uid != self.uid:
            ob = next((o for o in bpy.data.objects if o.session_uid == self.uid), None)
        if ob is not None:
            self.name = ob.name
        return ob

    def require(self, what: str = "object") -> bpy.types.Object:
        """The object; a :class:`RuntimeError` naming it (one line for the user) if it was deleted."""
        ob = self.get()
        if ob is None:
            raise RuntimeError(f"the {what} '{self.name}' was deleted while the job ran; nothing was written")
        return ob


STAGE_TEXT = {
    "start": "starting",
    "read": "reading the crease pattern file",
    "discretise": "discretising the crease curves",
    "mesh": "meshing the pattern",
    "model": "building the bar-and-hinge model",
    "figures": "measuring the fold (strain, warp, self-intersection)",
    "setup": "preparing the export scene",
    "export": "Blender's exporter is writing the file",
    "write": "writing the file",
}
"""The status-bar line of the stages that say no more than their name (:meth:`Progress.text`)."""


@dataclass
class Progress:
    """Where a job is: its ``stage`` ("start", "read" (an import), "discretise", "mesh", "model", "solve", "figures",
    "frame", and an export's "encode", "setup", "export", "write"), the solver iteration and residual, the frame k
    of n (bakes, exports), the fraction done, and positions (mm) worth showing (or None).

    ``alone``: the unit that follows runs in a slice of its own (:func:`run_slice` ends the slice before it): a
    single call into Blender's own exporter, which cannot be split, is not added to a slice's other work."""

    stage: str
    iteration: int = 0
    residual: float = math.nan
    frame: int = 0
    n_frames: int = 0
    fraction: float = 0.0
    positions: np.ndarray | None = None
    alone: bool = False

    def text(self, elapsed_s: float = 0.0) -> str:
        """One status-bar line: iteration and residual, or frame k of n with the time left."""
        if self.stage in STAGE_TEXT:
            return STAGE_TEXT[self.stage]
        if self.stage == "encode" and self.n_frames:
            if not self.frame:
                return "encoding the crease pattern"
            return f"encoding frame {self.frame} of {self.n_frames}"
        if self.stage == "frame" and self.n_frames:
            left = ""
            if self.fraction > 0 and elapsed_s > 0:
                left = f", {elapsed_s * (1.0 - self.fraction) / self.fraction:.0f} s left"
            return f"frame {self.frame} of {self.n_frames}{left}"
        res = f", residual {self.residual:.2e}" if math.isfinite(self.residual) else ""
        return f"iteration {self.iteration}{res}"


JobSteps = Generator[Progress, None, Callable[[], Any]]


class PositionsPreview:
    """Intermediate positions shown on an existing fold object; :meth:`restore` puts back the exact bytes.

    Captured: the ``position`` attribute, the reference shape key, the mute flags of the shape keys (a bake would
    hide the preview, so the preview mutes it) and the points of the crease-curve children."""

    def __init__(self, ob: bpy.types.Object, scene: bpy.types.Scene | None = None):
        self.handle = ObjectHandle(ob)
        self.scene = scene
        me = ob.data
        self.n = len(me.vertices)
        self.position = np.empty(3 * self.n, dtype=np.float32)
        me.attributes["position"].data.foreach_get("vector", self.position)
        keys = me.shape_keys
        self.reference = None
        self.mutes: dict[str, bool] = {}
        if keys is not None:
            self.reference = np.empty(3 * self.n, dtype=np.float32)
            keys.reference_key.points.foreach_get("co", self.reference)
            self.mutes = {k.name: k.mute for k in keys.key_blocks}
        self.children: dict[str, list[np.ndarray]] = {}
        for name, child in mesh_object._crease_curve_objects(ob).items():
            pts = []
            for sp in child.data.splines:
                co = np.empty(4 * len(sp.points), dtype=np.float32)
                sp.points.foreach_get("co", co)
                pts.append(co)
            self.children[name] = pts
        self.origin = mesh_object.origin_state(ob)
        self.shown = False

    @property
    def ob(self) -> bpy.types.Object | None:
        return self.handle.get()

    def edited(self) -> bpy.types.Object | None:
        """The object whose mesh this preview changes (None if gone)."""
        return self.ob

    def show(self, positions_mm: np.ndarray) -> None:
        ob = self.ob
        if ob is None or len(positions_mm) != self.n:
            return
        keys = ob.data.shape_keys
        if keys is not None:
            for k in keys.key_blocks[1:]:
                k.mute = True
        mesh_object.update_positions(ob, positions_mm, scene=self.scene)
        self.shown = True

    def restore(self) -> None:
        ob = self.ob
        if ob is None or not self.shown:
            return
        me = ob.data
        keys = me.shape_keys
        if keys is not None and self.reference is not None:
            keys.reference_key.points.foreach_set("co", self.reference)
            for k in keys.key_blocks:
                if k.name in self.mutes:
                    k.mute = self.mutes[k.name]
        me.attributes["position"].data.foreach_set("vector", self.position)
        me.update()
        for name, child in mesh_object._crease_curve_objects(ob).items():
            for sp, co in zip(child.data.splines, self.children.get(name, ()), strict=False):
                sp.points.foreach_set("co", co)
            child.data.update_tag()
        mesh_object.restore_origin_state(ob, self.origin)  # the previews recorded their writes
        self.shown = False


class MeshPreview:
    """A mesh not in the scene yet (a new fold, or a rebuilt pattern) shown while it folds.

    With ``ob`` (a rebuild) the object temporarily shows a preview mesh datablock instead of its own; without, a
    temporary object is linked into ``collection``. :meth:`restore` removes every datablock it made."""

    def __init__(
        self,
        name: str,
        *,
        ob: bpy.types.Object | None = None,
        collection: bpy.types.Collection | None = None,
        place=None,
        scene: bpy.types.Scene | None = None,
    ):
        self.name = name
        self.handle = ObjectHandle(ob) if ob is not None else None
        self.collection = collection
        self.collection_name = collection.name if collection is not None else ""
        self.place = place
        self.scene = scene
        self.mesh = None
        self.me_name: str | None = None
        self.tmp: ObjectHandle | None = None
        self.old_me_name: str | None = None
        self.offset = np.zeros(3)  # BU: the object's origin offset (mesh_object.local_offset), for a rebuild

    def edited(self) -> bpy.types.Object | None:
        """The object whose mesh this preview changes: the rebuilt object, or the temporary one (None if none)."""
        if self.handle is not None:
            return self.handle.get()
        return self.tmp.get() if self.tmp is not None else None

    def set_mesh(self, mesh) -> None:
        """The FoldMesh the following :meth:`show` calls move (made once the pattern is meshed)."""
        self.mesh = mesh

    def _make(self, positions_mm: np.ndarray) -> None:
        if self.handle is not None:  # a rebuild: shown where the object's origin puts its vertices
            self.offset = mesh_object.local_offset(self.handle.require())
        me = mesh_object._new_mesh_data(self.mesh, positions_mm, f"{self.name} (folding)", self.scene, self.offset)
        self.me_name = me.name
        if self.handle is not None:
            ob = self.handle.require()
            self.old_me_name = ob.data.name
            for mat in ob.data.materials:
                me.materials.append(mat)
            ob.data = me
        else:
            ob = bpy.data.objects.new(f"{self.name} (folding)", me)
            try:
                (self.collection or bpy.context.scene.collection).objects.link(ob)
            except ReferenceError:  # the collection was deleted while the job ran
                bpy.data.objects.remove(ob)
                bpy.data.meshes.remove(me)
                self.me_name = None
                raise RuntimeError(
                    f"the collection '{self.collection_name}' was deleted while the job ran; nothing was written"
                ) from None
            self.tmp = ObjectHandle(ob)
            if self.place is not None:
                self.place(ob)

    def show(self, positions_mm: np.ndarray) -> None:
        if self.mesh is None or len(positions_mm) != self.mesh.n_vertices:
            return
        if self.me_name is None:
            self._make(positions_mm)
            return
        me = bpy.data.meshes.get(self.me_name)
        if me is None:
            return
        co = np.asarray(positions_mm, dtype=np.float64) / mesh_object.mm_per_unit(self.scene) + self.offset
        me.attributes["position"].data.foreach_set("vector", co.astype(np.float32).ravel())
        me.update()

    def restore(self) -> None:
        if self.me_name is None:
            return
        if self.handle is not None and self.old_me_name is not None:
            ob = self.handle.get()
            old = bpy.data.meshes.get(self.old_me_name)
            if ob is not None and old is not None:
                ob.data = old
        if self.tmp is not None:
            tmp = self.tmp.get()
            if tmp is not None:
                bpy.data.objects.remove(tmp)
        me = bpy.data.meshes.get(self.me_name)
        if me is not None and me.users == 0:
            bpy.data.meshes.remove(me)
        self.me_name = self.tmp = self.old_me_name = None


class Job:
    """One running piece of work on one folded object (``owner``: its name, or the name a new fold will take)."""

    def __init__(self, owner: str, kind: str, steps: JobSteps, preview=None, *, live: bool = False):
        self.owner = owner
        self.kind = kind
        self.steps = steps
        self.preview = preview
        self.live = live
        self.state = "running"
        self.progress = Progress("start")
        self.result: Any = None
        self.pending_commit: Callable[[], Any] | None = None
        """The commit, once the work is done, when it is left for the next slice (:func:`run_slice`)."""
        self.error: BaseException | None = None
        self.cancel_reason = ""
        """Why the job was cancelled, when not by its user (a save): the modal operator reports it."""
        self.slices = 0
        self.units = 0
        self.longest_slice_ms = 0.0
        self.unit_ms: dict[str, float] = {}
        """Longest unit of work per stage ("start" is the first unit: reading the curves for a fold or a rebuild,
        "discretise" a step of their discretisation, "mesh" the triangulation, "model" the bar-and-hinge model and
        the Hessian's structure, "solve" a solver iteration, "figures" the self-intersection test or the report)."""
        self.started = time.perf_counter()
        self.elapsed_ms = 0.0
        self.shown: np.ndarray | None = None
        """The positions the preview shows (mm), to show again after a save (:func:`hide_previews`)."""

    @property
    def running(self) -> bool:
        return self.state == "running"

    def status(self) -> str:
        """The status-bar line of this job."""
        return f"Curved Fold: {self.kind} '{self.owner}' — {self.progress.text(self.elapsed_ms / 1e3)}"


_jobs: dict[str, Job] = {}
"""Running jobs: owner name → job (one per folded object)."""


def running_job(owner: str) -> Job | None:
    """The job running on ``owner`` (a fold object's name), if any."""
    job = _jobs.get(owner)
    return job if job is not None and job.running else None


def job_on(ob: bpy.types.Object) -> Job | None:
    """The job running on ``ob``: the one owned by its name, else one whose preview changes it (a job started
    before the object was renamed is owned by the old name)."""
    job = running_job(ob.name)
    if job is not None:
        return job
    return next((j for j in _jobs.values() if j.running and _previews(j, ob.session_uid)), None)


def free_owner(name: str) -> str:
    """An owner for a job that makes a new object called ``name``: ``name`` itself, or the first ``name.001``,
    ``name.002`` … that no object has and no job owns (Blender numbers the new object so when the name is taken).
    Owned by the existing object's name, a Fold of curves whose earlier fold was baking was refused as "busy"."""
    candidate, k = name, 0
    while candidate in bpy.data.objects or candidate in _jobs:
        k += 1
        candidate = f"{name}.{k:03d}"
    return candidate


def _previews(job: Job, uid: int) -> bool:
    """Whether ``job``'s preview changes the object with ``session_uid`` ``uid``."""
    ob = job.preview.edited() if job.preview is not None else None
    return ob is not None and ob.session_uid == uid


def stop_live(ob: bpy.types.Object | None) -> None:
    """Cancel the live jobs (a frame job, a live re-fold) showing their work on ``ob``, found by the object itself,
    not by the name they were started under: call it before a new job on ``ob`` snapshots the object, so the new
    job's Esc restores the shape from before the live one (a Bake started while a frame job showed a half-folded
    frame restored that frame), and a job started before a rename is not left running beside the new one."""
    if ob is None:
        return
    for job in list(_jobs.values()):
        if job.running and job.live and _previews(job, ob.session_uid):
            cancel(job)


def start(job: Job) -> Job:
    """Register ``job`` as its owner's one job. A running live job on the owner, or showing its work on the same
    object (:func:`stop_live`), is cancelled (superseded); any other running job there, also one started under the
    object's old name (:func:`job_on`: an export renamed mid-job ran on beside a Bake), raises
    :class:`JobBusyError`."""
    target = job.preview.edited() if job.preview is not None else None
    stop_live(target)
    old = running_job(job.owner)
    if old is None and target is not None:  # a job started on the object before it was renamed
        old = job_on(target)
    if old is not None and old is not job:
        if not old.live:
            raise JobBusyError(f"'{job.owner}' is busy ({old.kind}); wait for it or press Esc to cancel it")
        cancel(old)
    _jobs[job.owner] = job
    return job


class EditModeError(RuntimeError):
    """The object a job previews on was put in Edit Mode: the job stops (one line for the user)."""


def _leave_edit_mode(ob: bpy.types.Object) -> None:
    """Take ``ob`` out of Edit Mode (writing its edit mesh back, as Tab does), the active object kept."""
    view_layer = bpy.context.view_layer
    active = view_layer.objects.active
    view_layer.objects.active = ob
    try:
        bpy.ops.object.mode_set(mode="OBJECT")
    finally:
        if active is not None and active != ob and bpy.data.objects.get(active.name) is active:
            view_layer.objects.active = active


def _in_edit_mode(job: Job) -> bpy.types.Object | None:
    """The object ``job``'s preview changes, if it is in Edit Mode (else None)."""
    ob = job.preview.edited() if job.preview is not None else None
    return ob if ob is not None and ob.mode == "EDIT" else None


def _restore(job: Job) -> None:
    """Restore ``job``'s preview, leaving Edit Mode first if its object was put there (in Edit Mode the mesh's
    arrays are empty and the restore failed: a Bake under Tab stayed "busy" for good)."""
    if job.preview is None:
        return
    ob = _in_edit_mode(job)
    if ob is not None:
        _leave_edit_mode(ob)
    job.preview.restore()


def _check_not_edited(job: Job) -> None:
    """Raise :class:`EditModeError` if the object ``job`` previews on is in Edit Mode (its next write would be lost,
    or fail)."""
    ob = _in_edit_mode(job)
    if ob is not None:
        raise EditModeError(
            f"'{ob.name}' was put in Edit Mode while {job.kind}: stopped; it is back in Object Mode as it was"
        )


def _end(job: Job, state: str) -> None:
    job.state = state
    job.elapsed_ms = 1e3 * (time.perf_counter() - job.started)
    if _jobs.get(job.owner) is job:
        del _jobs[job.owner]


def run_slice(job: Job, budget_ms: float | None = None) -> bool:
    """Advance ``job`` by units of work while the next one, expected to take as long as the longest of its kind so far
    (as the last unit, for the first of a kind), ends within ``budget_ms`` (default :data:`SLICE_MS`; at least one
    unit); show the positions reached; commit when the work is done. Returns True when the job has ended.

    An error restores the preview, ends the job (``state == "failed"``, ``job.error``) and is raised again."""
    if not job.running:
        return True
    if budget_ms is None:
        budget_ms = SLICE_MS
    t0 = time.perf_counter()
    shown = None
    commit = job.pending_commit
    ran = 0
    try:
        _check_not_edited(job)
        while commit is None:
            tu = time.perf_counter()
            try:
                progress = next(job.steps)
            except StopIteration as done:
                commit = done.value
                unit = job.progress.stage  # the last unit did work too (an export's write): its time counts
                job.unit_ms[unit] = max(job.unit_ms.get(unit, 0.0), 1e3 * (time.perf_counter() - tu))
                if ran and callable(commit):
                    # the commit writes the scene (an import's objects: ~50 ms for 2,254 lines): in a slice of its
                    # own, not after this slice's units (an import's slice reached 118 ms)
                    job.pending_commit, commit = commit, None
                break
            ran += 1
            unit = job.progress.stage  # the label of the unit just done (a progress names the work that follows)
            now = time.perf_counter()
            unit_ms = 1e3 * (now - tu)
            job.unit_ms[unit] = max(job.unit_ms.get(unit, 0.0), unit_ms)
            job.units += 1
            job.progress = progress
            if progress.positions is not None:
                shown = progress.positions
            # the next unit, as long as the longest of its kind so far (or as this one, if it is the first), would
            # overrun: a bake's frame units vary (a warm iteration 20 ms, the one after a grid point 60 ms), and
            # predicting from the last unit let slices reach 110 ms
            if progress.alone or 1e3 * (now - t0) + job.unit_ms.get(progress.stage, unit_ms) >= budget_ms:
                break
        if commit is None:
            if shown is not None and job.preview is not None:
                job.preview.show(shown)
                job.shown = shown
        else:
            if job.preview is not None:
                job.preview.restore()
            job.result = commit() if callable(commit) else commit
    except BaseException as exc:
        try:
            _restore(job)
        except Exception as failed:  # noqa: BLE001 - the scene changed under the preview too: the job still ends
            exc.add_note(f"restoring the preview failed: {type(failed).__name__}: {failed}")
        job.error = exc
        job.steps.close()
        _end(job, "failed")
        raise
    finally:
        job.slices += 1
        job.longest_slice_ms = max(job.longest_slice_ms, 1e3 * (time.perf_counter() - t0))
        job.elapsed_ms = 1e3 * (time.perf_counter() - job.started)
    if commit is not None:
        _end(job, "done")
        return True
    return False


def drop(job: Job) -> None:
    """End ``job`` without restoring its preview: the shape it shows stays (a frame job whose object the user took
    into Edit Mode keeps the shape they are editing; restoring would mean throwing them out of Edit Mode)."""
    if not job.running:
        return
    job.steps.close()
    _end(job, "cancelled")


def cancel(job: Job, reason: str = "") -> None:
    """Stop ``job`` between slices: close its generator and restore what its preview changed. Nothing else was
    written (only the commit writes), so the scene is as it was before the job. ``reason``: why, when the user did
    not ask (the modal operator reports it)."""
    if not job.running:
        return
    job.cancel_reason = reason
    job.steps.close()
    try:
        _restore(job)
    finally:
        _end(job, "cancelled")


def run_to_end(job: Job) -> Any:
    """The blocking path: run ``job`` to its end (same slices, no budget) and return what its commit returned."""
    while not run_slice(job, math.inf):
        pass
    return job.result


def hide_previews() -> None:
    """Before a save: every running job's preview restored, so the file holds the scene as it was before the job
    (:func:`show_previews` puts the previews back after it). Saved with a bake running, the file held its muted
    keys and a partial frame; saved during a rebuild, the object pointed at the temporary mesh and the bake's keys
    were not in the file (a designer session's Ctrl+S). A job whose object is in Edit Mode is cancelled: its
    preview could not be shown again there (:func:`cancel` takes the object out of Edit Mode to restore it). So is
    a job whose preview holds temporary datablocks (an export's scene: ``holds_datablocks``), which the file
    would otherwise keep."""
    for job in list(_jobs.values()):
        if job.running and job.preview is not None:
            if _in_edit_mode(job) is not None:
                cancel(job)
            elif getattr(job.preview, "holds_datablocks", False):
                cancel(job, "the file was saved while it held its temporary scene; nothing was written, run it again")
            else:
                job.preview.restore()


def show_previews() -> None:
    """After a save: the running jobs' previews shown again where they were (:func:`hide_previews`)."""
    for job in _jobs.values():
        if job.running and job.preview is not None and job.shown is not None:
            job.preview.show(job.shown)


def cancel_all() -> None:
    """Cancel every running job (add-on unregistered, file loaded)."""
    for job in list(_jobs.values()):
        cancel(job)
