"""Cancellable jobs and the timeline (issue 13), headless: timers and modal loops do not run here, so the slice
function is driven directly and the operators run through ``bpy.ops`` (EXEC_DEFAULT, the blocking path).

* a slice advances a job (the viewport preview moves) and cancel restores the scene byte for byte, for a fresh
  fold, a re-solve (with a bake on the object) and a re-mesh after a curve edit;
* the sliced work equals the blocking work (the Newton iterations, the faithful integrator in chunks);
* one job per folded object: a second job is refused, a new live edit supersedes a running live job;
* keyframed Fold Percent: a frame change folds the mesh before any bake, equal to a cold solve at that percent;
  the bake equals the cached frames;
* Live on (and a live re-fold) keeps the bake, marked out of date; Re-bake makes it current.
"""

from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from .test_operators import curved_pattern, evaluated_mm, mod, select_only, snapshot  # noqa: E402

pytestmark = pytest.mark.usefixtures("extension")


def _plain(value):
    """An ID property's content (a group's repr names its address, which a file read back does not keep)."""
    return value.to_dict() if hasattr(value, "to_dict") else value


def exact_state() -> dict:
    """``snapshot()`` plus the raw bytes (unrounded) of every mesh's positions and shape keys, the key mute flags,
    the crease-curve points and the objects' ID properties: what "restored byte for byte" compares."""
    state = snapshot()
    for ob in bpy.data.objects:
        extra = [sorted((k, repr(_plain(ob[k]))) for k in ob.keys() if k.startswith("cf_"))]
        if ob.type == "MESH":
            me = ob.data
            co = np.empty(3 * len(me.vertices), dtype=np.float32)
            me.attributes["position"].data.foreach_get("vector", co)
            extra.append(co.tobytes())
            if me.shape_keys is not None:
                for k in me.shape_keys.key_blocks:
                    kc = np.empty(3 * len(me.vertices), dtype=np.float32)
                    k.points.foreach_get("co", kc)
                    extra.append((k.name, k.mute, k.value, kc.tobytes()))
        if ob.type == "CURVE":
            for sp in ob.data.splines:
                pc = np.empty(4 * len(sp.points), dtype=np.float32)
                sp.points.foreach_get("co", pc)
                extra.append(pc.tobytes())
        state[ob.name].append(extra)
    state["mesh users"] = sorted((m.name, m.users, m.use_fake_user) for m in bpy.data.meshes)
    return state


@pytest.fixture
def folded(extension, clean_scene):
    border, crease = curved_pattern()
    select_only([border, crease])
    assert bpy.ops.curved_fold.fold() == {"FINISHED"}
    return bpy.context.active_object, border, crease


def positions_mm(ob) -> np.ndarray:
    co = np.empty(3 * len(ob.data.vertices), dtype=np.float32)
    ob.data.attributes["position"].data.foreach_get("vector", co)
    return co.reshape(-1, 3).astype(np.float64) * 1000.0


def run_slices_until(jobs, job, stage: str, then: int = 0) -> None:
    """One unit per slice (zero budget) until the job's progress reaches ``stage``, then ``then`` slices more."""
    for _ in range(200):
        if job.progress.stage == stage:
            break
        assert not jobs.run_slice(job, budget_ms=0.0)
    assert job.progress.stage == stage
    for _ in range(then):
        assert not jobs.run_slice(job, budget_ms=0.0)


def test_fold_job_slices_preview_and_cancel_restores(extension, clean_scene):
    jobs = mod(extension, "scene.jobs")
    folding = mod(extension, "scene.folding")
    border, crease = curved_pattern()
    select_only([border, crease])
    before = exact_state()
    job = jobs.start(folding.fold_job([border, crease], None, folding.FoldOptions(), scene=clean_scene))
    seen = []
    stages = []
    while stages.count("solve") < 5:  # curves read, 4 discretisation steps, mesh, model, then Newton iterations:
        # the preview object appears and moves
        assert not jobs.run_slice(job, budget_ms=0.0)
        stages.append(job.progress.stage)
        preview = bpy.data.objects.get("Border Folded (folding)")
        if preview is not None:
            seen.append(positions_mm(preview)[:, 2].copy())
        assert len(stages) < 200
    # one unit per slice at a zero budget; the mesh is several units (the triangulation, the swaps, the cuts), so
    # is the model (the model, the Hessian's ordering one component at a time, its structure, the scatter indices)
    meshes, models = stages.count("mesh"), stages.count("model")
    assert meshes >= 2 and models >= 3
    assert stages[: 6 + meshes + models] == ["discretise"] * 5 + ["mesh"] * meshes + ["model"] * models + ["solve"]
    assert job.progress.stage == "solve" and job.progress.iteration >= 1 and np.isfinite(job.progress.residual)
    # the preview shows the sheet folding and moving from slice to slice (not necessarily monotonically: a Newton
    # step can overshoot the fold and the next take some of it back)
    assert "iteration" in job.status() and len(seen) >= 2 and np.ptp(seen[-1]) > 1.0
    assert np.abs(seen[-1] - seen[0]).max() > 1e-3
    jobs.cancel(job)
    assert exact_state() == before and bpy.data.objects.get("Border Folded (folding)") is None
    # The same job run to its end (the blocking path) creates the fold object, equal to the operator's.
    ob, out = jobs.run_to_end(jobs.start(folding.fold_job([border, crease], None, folding.FoldOptions())))
    assert ob.name == "Border Folded" and bpy.data.objects.get("Border Folded (folding)") is None
    np.testing.assert_allclose(positions_mm(ob), out.positions, atol=1e-3)
    assert out.report["iterations"] == ob.curved_fold_mesh.last_iterations > 0


def test_refold_job_cancel_restores_bake_and_positions(folded, extension):
    """A re-solve at another percent on an object with a bake: the preview moves the sheet (and mutes the bake so it
    shows); cancel restores positions, keys and mute flags exactly."""
    ob, _, _ = folded
    jobs = mod(extension, "scene.jobs")
    folding = mod(extension, "scene.folding")
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 3
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    ob.curved_fold_mesh.fold_percent = 30.0
    before = exact_state()
    start_pos = positions_mm(ob)
    job = jobs.start(folding.refold_job(ob, rebuild=False, warm_start=True))
    run_slices_until(jobs, job, "solve", then=2)
    assert np.abs(positions_mm(ob) - start_pos).max() > 1e-3  # the viewport shows the sheet moving
    assert all(k.mute for k in ob.data.shape_keys.key_blocks if k.name.startswith("cf_frame_"))
    jobs.cancel(job)
    assert exact_state() == before


def _rebuild_shown(jobs, folding, ob, crease):
    """A crease curve edited, and the re-mesh it asks for started and run until its preview mesh is shown (curves
    read and 4 discretisation steps, mesh, model in several units, then a solve): ``(exact_state()`` before the job,
    the object's own mesh name, the job)."""
    crease.data.splines[0].bezier_points[1].handle_left = (0.08, 0.03, 0)
    bpy.context.view_layer.update()
    before, own = exact_state(), ob.data.name
    job = jobs.start(folding.refold_job(ob, rebuild=True, warm_start=True))
    run_slices_until(jobs, job, "solve", then=1)
    return before, own, job


def test_rebuild_job_cancel_restores_mesh(folded, extension):
    """A re-mesh after a curve edit previews a new mesh datablock on the object; cancel gives the object its own
    mesh back and removes the preview mesh."""
    ob, _, crease = folded
    jobs = mod(extension, "scene.jobs")
    folding = mod(extension, "scene.folding")
    before, own, job = _rebuild_shown(jobs, folding, ob, crease)
    assert ob.data.name != own  # the preview mesh is shown
    jobs.cancel(job)
    assert ob.data.name == own and exact_state() == before


def test_one_job_per_object_and_live_supersedes(folded, extension):
    ob, _, _ = folded
    jobs = mod(extension, "scene.jobs")
    folding = mod(extension, "scene.folding")
    first = jobs.start(folding.refold_job(ob, rebuild=False))
    with pytest.raises(jobs.JobBusyError, match="busy"):
        jobs.start(folding.refold_job(ob, rebuild=False))
    with pytest.raises(RuntimeError, match="busy"):  # the operator refuses with one line, scene unchanged
        bpy.ops.curved_fold.refold()
    jobs.cancel(first)
    before = exact_state()
    live1 = jobs.start(folding.refold_job(ob, rebuild=False, live=True, warm_start=True))
    jobs.run_slice(live1, budget_ms=0.0)
    live2 = jobs.start(folding.refold_job(ob, rebuild=False, live=True, warm_start=True))
    assert live1.state == "cancelled" and exact_state() == before  # superseded: its preview undone
    assert jobs.running_job(ob.name) is live2
    jobs.run_to_end(live2)
    assert live2.state == "done" and jobs.running_job(ob.name) is None


def test_sliced_solves_equal_one_call(folded, extension):
    """The units of a job are the solver's own: Newton iterations (fast) and chunks of explicit steps (faithful)
    give the result of one ``Solver.solve`` call."""
    ob, _, _ = folded
    folding = mod(extension, "scene.folding")
    solver_mod = mod(extension, "core.solve.solver")
    mesh = mod(extension, "scene.mesh_object").read_fold_mesh(ob)

    def drain(gen):
        n = 0
        while True:
            try:
                next(gen)
                n += 1
            except StopIteration as done:
                return done.value, n

    fast, n_fast = drain(folding.solve_progress(solver_mod.Solver(mesh), 0.7))
    ref = solver_mod.Solver(mesh).solve(0.7)
    assert n_fast == ref.iterations and np.array_equal(fast.positions, ref.positions)
    settings = solver_mod.SolverSettings(max_steps=1500, tolerance=1e-9)
    faithful, n_chunks = drain(folding.solve_progress(solver_mod.Solver(mesh, settings, "faithful"), 0.7, chunk_ms=0))
    ref = solver_mod.Solver(mesh, settings, "faithful").solve(0.7)
    assert n_chunks >= 10 and faithful.iterations == ref.iterations
    np.testing.assert_allclose(faithful.positions, ref.positions, rtol=0, atol=1e-9)


def keyframe_percent(ob, values: dict[int, float]) -> None:
    props = ob.curved_fold_mesh
    for frame, value in values.items():
        props.fold_percent = value
        props.keyframe_insert("fold_percent", frame=frame)


def test_frame_change_folds_keyframed_percent_and_bake_equals_cache(folded, extension):
    ob, _, _ = folded
    scene = bpy.context.scene
    timeline = mod(extension, "scene.timeline")
    solver_mod = mod(extension, "core.solve.solver")
    scene.frame_start, scene.frame_end = 1, 9
    keyframe_percent(ob, {1: 10.0, 9: 90.0})
    assert timeline.on_frame_change in bpy.app.handlers.frame_change_post
    assert ob.data.shape_keys is None  # no bake
    mesh = timeline.cache_for(ob).mesh
    diag = float(np.linalg.norm(np.ptp(mesh.vertices_3d, axis=0)))
    heights = []
    for frame in (5, 2, 9, 7):
        scene.frame_set(frame)  # frame_change_post folds the mesh to this frame's percent
        pct = timeline.percent_at(ob, frame)
        cold = solver_mod.Solver(mesh).solve(pct).positions
        got = positions_mm(ob)
        assert solver_mod.rigid_rms(got, cold) / diag <= 1e-4, frame
        heights.append(np.ptp(got[:, 2]))
    assert heights[1] < heights[0] < heights[3] < heights[2]  # frames 2 < 5 < 7 < 9 fold further
    cache = timeline.cache_for(ob)
    assert sorted(cache.frames) == [2, 5, 7, 9]
    # the first frame is folded along the natural path: the static fold (with the props' float32 settings), exactly
    static = solver_mod.Solver(mesh, cache.solver(ob.curved_fold_mesh).settings).solve(timeline.percent_at(ob, 5))
    assert np.array_equal(cache.frames[5].positions, static.positions)
    cached = {f: cache.frames[f].positions.copy() for f in cache.frames}
    # Bake: the cached frames are taken as they are, the others solved (and cached).
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    assert sorted(cache.frames) == list(range(1, 10))
    for frame in range(1, 10):
        scene.frame_set(frame)
        np.testing.assert_allclose(evaluated_mm(ob), cache.frames[frame].positions, atol=5e-3)
        if frame in cached:
            assert np.array_equal(cache.frames[frame].positions, cached[frame])
    # With a current bake, frame changes show the bake and solve nothing.
    assert not timeline.driven(ob)
    # A settings change is not served from the cache: solved again with the new settings.
    assert cache.get(5, timeline.percent_at(ob, 5), ob.curved_fold_mesh) is not None
    ob.curved_fold_mesh.crease_stiffness = 1.4
    assert cache.get(5, timeline.percent_at(ob, 5), ob.curved_fold_mesh) is None


def test_a_frame_that_playback_leaves_unconverged_says_so(folded, extension, monkeypatch):
    """Playback stops a frame at ``FRAME_MAX_ITERATIONS``: the panel said nothing and kept the static fold's
    figures (a designer session: 16 of 60 frames unconverged on Carved_Cylinder). The frame's note says so now,
    and the next converged frame clears it (not other messages)."""
    ob, _, _ = folded
    timeline = mod(extension, "scene.timeline")
    props = ob.curved_fold_mesh
    keyframe_percent(ob, {1: 10.0, 9: 90.0})
    bpy.context.scene.frame_set(5)
    assert props.last_message == ""
    monkeypatch.setattr(timeline, "FRAME_MAX_ITERATIONS", 1)  # a warm frame after it gets one iteration
    bpy.context.scene.frame_set(6)
    assert props.last_message.startswith("frame 6: not converged in playback's 1 iterations (residual ")
    assert props.last_message.endswith("; Bake solves it fully")
    monkeypatch.setattr(timeline, "FRAME_MAX_ITERATIONS", 12)
    timeline.clear()
    bpy.context.scene.frame_set(7)
    assert props.last_message == ""
    props.last_message = "an earlier warning"
    bpy.context.scene.frame_set(8)
    assert props.last_message == "an earlier warning"


def test_a_frame_the_user_steps_to_folds_in_slices_and_ends_converged(folded, extension, monkeypatch):
    """In the interface a frame change of an unbaked keyframed fold held Blender for the whole solve (200–460 ms a
    frame on a 3,000-face pleat) and showed a frame cut short at 12 iterations. Now a frame the user steps or
    scrubs to (no playback, no render) is a job: one slice in the handler, the rest on a timer, ending in the bake's
    converged frame; the next frame change, a Bake or its Cancel button supersede it, and a superseded or cancelled
    frame leaves the shape as it was and nothing cached."""
    ob, _, _ = folded
    scene = bpy.context.scene
    timeline = mod(extension, "scene.timeline")
    jobs = mod(extension, "scene.jobs")
    solver_mod = mod(extension, "core.solve.solver")
    scene.frame_start, scene.frame_end = 1, 9
    keyframe_percent(ob, {1: 10.0, 9: 90.0})
    monkeypatch.setattr(timeline, "interactive", lambda: True)
    monkeypatch.setattr(jobs, "SLICE_MS", 0.0)  # one Newton iteration (or model unit) per slice
    before = positions_mm(ob)
    scene.frame_set(5)
    job5 = jobs.running_job(ob.name)
    assert job5 is not None and job5.kind == "folding frame 5" and job5.live and job5.slices == 1
    assert timeline.driven(ob)  # its own frame job does not stop the next frame change
    scene.frame_set(7)  # supersedes frame 5's job: its preview restored, nothing cached for frame 5
    assert job5.state == "cancelled"
    job7 = jobs.running_job(ob.name)
    assert job7.kind == "folding frame 7" and 5 not in timeline.cache_for(ob).frames
    slices = 1
    while timeline.drive_frames():
        slices += 1
        assert slices < 500
    assert job7.state == "done" and slices > 3
    cache = timeline.cache_for(ob)
    entry = cache.frames[7]
    assert entry.converged  # a bake's frame: from the natural path, the static fold at its percent, exactly
    static = solver_mod.Solver(cache.mesh, cache.solver(ob.curved_fold_mesh).settings).solve(timeline.percent_at(ob, 7))
    assert np.array_equal(entry.positions, static.positions)
    np.testing.assert_allclose(positions_mm(ob), entry.positions, atol=1e-3)
    scene.frame_set(7)  # solved: shown at once, no job
    assert jobs.running_job(ob.name) is None
    # The Cancel button (or Esc's equivalent for a timer job) leaves the shape of frame 7 as it was.
    shown = positions_mm(ob)
    scene.frame_set(3)
    job3 = jobs.running_job(ob.name)
    assert job3 is not None and not np.array_equal(positions_mm(ob), shown)
    assert bpy.ops.curved_fold.cancel_job(owner=ob.name) == {"FINISHED"}
    assert job3.state == "cancelled" and np.array_equal(positions_mm(ob), shown)
    assert not timeline.drive_frames()
    # A Bake supersedes a running frame job.
    scene.frame_set(2)
    job2 = jobs.running_job(ob.name)
    assert job2 is not None
    assert bpy.ops.curved_fold.bake() == {"FINISHED"} and job2.state == "cancelled"
    assert not np.array_equal(before, positions_mm(ob))


def test_a_frame_change_from_python_stays_synchronous(folded, extension, monkeypatch):
    """A script's, an exporter's or a ``bpy.ops`` call's ``frame_set`` reads the mesh right after it: such a frame
    change folds the frame before it returns, even in the interface. Only a frame change Blender makes for the user
    (the handler called from Blender's own code, nothing of Python below it) is left to a timer."""
    import _thread
    import threading

    ob, _, _ = folded
    scene = bpy.context.scene
    timeline = mod(extension, "scene.timeline")
    jobs = mod(extension, "scene.jobs")
    keyframe_percent(ob, {1: 10.0, 9: 90.0})
    asked = []
    monkeypatch.setattr(timeline, "_ui_idle", lambda: asked.append(True) or True)
    scene.frame_set(5)  # from Python: folded at once, no job, the idle window not even asked about
    assert jobs.running_job(ob.name) is None and asked == []
    assert timeline.cache_for(ob).frames[5].converged
    assert timeline._called_from_python()
    # Called as Blender calls it, with no Python frame below the handler (a thread started from C): left to a timer.
    seen, looked, pause = [], [], threading.Event()
    monkeypatch.setattr(timeline, "_ui_idle", lambda: seen.append(timeline._called_from_python()) or False)
    monkeypatch.setattr(timeline, "_follows_timeline", lambda o: looked.append(o.name) and False)  # touch nothing
    n_objects = len(scene.objects)
    _thread.start_new_thread(timeline.on_frame_change, (scene,))
    for _ in range(500):  # until the handler has looked at every object: it has nothing left to do
        if len(looked) == n_objects:
            break
        pause.wait(0.01)
    assert seen == [False] and len(looked) == n_objects


def _stepped_mid_job(extension, ob, monkeypatch, to: int = 8):
    """Frame 5 solved (from Python), then the user steps to ``to``: its frame job has shown two slices. Returns
    (timeline, jobs, the frame job, frame 5's positions)."""
    timeline = mod(extension, "scene.timeline")
    jobs = mod(extension, "scene.jobs")
    keyframe_percent(ob, {1: 10.0, 9: 90.0})
    bpy.context.scene.frame_set(5)
    shown5 = positions_mm(ob)
    monkeypatch.setattr(jobs, "SLICE_MS", 0.0)
    monkeypatch.setattr(timeline, "interactive", lambda: True)
    bpy.context.scene.frame_set(to)
    monkeypatch.setattr(timeline, "interactive", lambda: False)
    timeline.drive_frames()
    job = jobs.running_job(ob.name)
    assert job is not None and job.kind == f"folding frame {to}" and not np.array_equal(positions_mm(ob), shown5)
    return timeline, jobs, job, shown5


def test_a_frame_job_gives_way_to_the_users_next_step_whatever_it_is(folded, extension, monkeypatch, tmp_path):
    """A designer reviewer's session with the frame jobs: a Bake or Re-fold started while a frame job showed a
    half-folded frame took that frame as its "before" (Esc left it); renamed mid-job, the frame job was found by
    no one and went on beside a Bake, muting its keys; a stiffness edited mid-job cached the frame under the new
    settings; an export right after a step wrote the frame before; a save wrote the previous frame's shape at the
    new frame; Tab into Edit Mode threw the user back out. Each now ends the frame job as the user needs."""
    ob, _, _ = folded
    scene = bpy.context.scene
    bake = mod(extension, "scene.bake")
    folding = mod(extension, "scene.folding")
    scene.frame_start, scene.frame_end = 1, 9
    timeline, jobs, job, shown5 = _stepped_mid_job(extension, ob, monkeypatch)
    # a Bake (or Re-fold) made now snapshots frame 5's shape, not the half-folded one: its Esc restores frame 5
    for make in (lambda: bake.bake_job(ob, range(1, 10), scene=scene), lambda: folding.refold_job(ob, rebuild=False)):
        other = jobs.start(make())
        assert job.state == "cancelled" and np.array_equal(positions_mm(ob), shown5)
        jobs.run_slice(other, 0.0)
        jobs.cancel(other)
        assert np.array_equal(positions_mm(ob), shown5)
        timeline, jobs, job, shown5 = _stepped_mid_job(extension, ob, monkeypatch)
    # renamed mid-job: a Bake still supersedes it, and its keys are left as the bake made them
    ob.name = "Renamed mid-job"
    assert bpy.ops.curved_fold.bake() == {"FINISHED"} and job.state == "cancelled"
    assert not timeline.drive_frames()
    assert not any(k.mute for k in ob.data.shape_keys.key_blocks[1:]) and not bake.is_stale(ob)
    bpy.ops.curved_fold.clear_bake()
    # a stiffness edited mid-job: the frame is cached under the settings it was solved with
    timeline.clear()
    timeline, jobs, job, shown5 = _stepped_mid_job(extension, ob, monkeypatch)
    ob.curved_fold_mesh.crease_stiffness *= 3.0
    while timeline.drive_frames():
        pass
    cache = timeline.cache_for(ob)
    assert 8 in cache.frames and cache.get(8, timeline.percent_at(ob, 8), ob.curved_fold_mesh) is None
    ob.curved_fold_mesh.crease_stiffness /= 3.0
    assert cache.get(8, timeline.percent_at(ob, 8), ob.curved_fold_mesh) is not None
    # an export right after a step writes the frame the timeline is on (the job is finished first)
    timeline.clear()
    timeline, jobs, job, shown5 = _stepped_mid_job(extension, ob, monkeypatch, to=7)
    path = tmp_path / "frame7.obj"
    assert bpy.ops.curved_fold.export_folded(filepath=str(path), file_format="OBJ", unit="MM") == {"FINISHED"}
    assert job.state == "done"
    written = np.array(
        [[float(v) for v in line.split()[1:4]] for line in path.read_text().splitlines() if line.startswith("v ")]
    )
    frame7 = timeline.cache_for(ob).frames[7].positions
    assert np.ptp(written[:, 1]) == pytest.approx(np.ptp(frame7[:, 2]), rel=1e-3)  # OBJ is Y-up
    # a save finishes the frame job: the file holds the frame it is saved on
    timeline.clear()
    timeline, jobs, job, shown5 = _stepped_mid_job(extension, ob, monkeypatch, to=6)
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "mid.blend"), copy=True)
    assert job.state == "done"
    np.testing.assert_allclose(positions_mm(ob), timeline.cache_for(ob).frames[6].positions, atol=1e-3)
    # Tab into Edit Mode mid-job: the job ends and the user stays in Edit Mode, on the shape they see
    timeline.clear()
    timeline, jobs, job, shown5 = _stepped_mid_job(extension, ob, monkeypatch, to=4)
    bpy.context.view_layer.objects.active = ob
    bpy.ops.object.mode_set(mode="EDIT")
    assert not timeline.drive_frames()
    assert job.state == "cancelled" and ob.mode == "EDIT"
    bpy.ops.object.mode_set(mode="OBJECT")
    # the object deleted, or no longer driven (Dynamic mode), mid-job: the timer lets the job go
    timeline.clear()
    timeline, jobs, job, shown5 = _stepped_mid_job(extension, ob, monkeypatch, to=3)
    ob.curved_fold_mesh.solver_mode = "DYNAMIC"
    assert not timeline.drive_frames() and job.state == "cancelled"
    assert np.array_equal(positions_mm(ob), shown5)


def test_a_frame_stepped_to_while_another_job_runs_is_folded_when_it_ends(folded, extension, monkeypatch, tmp_path):
    """A frame the user stepped to while an export or a live re-fold ran on the object was passed by, and after
    that job the object showed the old frame's shape at the new frame until the next frame change (a reviewer
    session). Now the object is folded to the frame the timeline is on once the job ends; an object deleted or
    baked meanwhile is let go."""
    ob, _, _ = folded
    scene = bpy.context.scene
    timeline = mod(extension, "scene.timeline")
    jobs = mod(extension, "scene.jobs")
    export = mod(extension, "scene.export")
    keyframe_percent(ob, {1: 10.0, 9: 90.0})
    scene.frame_set(5)  # from Python: solved at once
    shown5 = positions_mm(ob)
    monkeypatch.setattr(jobs, "SLICE_MS", 0.0)
    monkeypatch.setattr(timeline, "interactive", lambda: True)
    monkeypatch.setattr(timeline, "_ui_idle", lambda: True)
    for make in (
        lambda: export.export_job(ob, tmp_path / "during.fold", scene=scene),
        lambda: mod(extension, "scene.folding").refold_job(ob, rebuild=False, warm_start=True, live=True),
    ):
        ob.curved_fold_mesh.crease_stiffness *= 1.5  # (the live re-fold's edit; frame 8 is not in the cache)
        other = jobs.start(make())
        jobs.run_slice(other, 0.0)
        scene.frame_set(8)  # the user steps on: passed by while the other job runs
        assert jobs.running_job(ob.name) is other and timeline.catch_up()  # still waiting for it
        jobs.run_to_end(other)
        assert other.state == "done"
        assert not timeline.catch_up()  # the other job is over: frame 8's job starts
        job8 = jobs.running_job(ob.name)
        assert job8 is not None and job8.kind == "folding frame 8"
        while timeline.drive_frames():
            pass
        frame8 = timeline.cache_for(ob).frames[8].positions
        np.testing.assert_allclose(positions_mm(ob), frame8, atol=1e-3)
        assert not np.allclose(frame8, shown5, atol=1e-2)
        scene.frame_set(5)
        while timeline.drive_frames():
            pass
    # the object and the scene renamed while the job runs: still waited for (no frame job beside the export), then
    # caught up; the object moved to another scene meanwhile follows that scene's frame
    other = jobs.start(export.export_job(ob, tmp_path / "renamed.fold", scene=scene))
    jobs.run_slice(other, 0.0)
    ob.name, scene.name = "Renamed mid-export", "Renamed scene"
    scene.frame_set(8)
    assert timeline.catch_up() and [j.kind for j in jobs._jobs.values() if j.running] == ["exporting"]
    with pytest.raises(jobs.JobBusyError, match="is busy \\(exporting\\)"):  # one job per object, whatever its name
        jobs.start(mod(extension, "scene.bake").bake_job(ob, range(1, 10), scene=scene))
    jobs.run_to_end(other)
    assert not timeline.catch_up()
    while timeline.drive_frames():
        pass
    np.testing.assert_allclose(positions_mm(ob), timeline.cache_for(ob).frames[8].positions, atol=1e-3)
    other = jobs.start(export.export_job(ob, tmp_path / "moved.fold", scene=scene))
    jobs.run_slice(other, 0.0)
    scene.frame_set(5)
    elsewhere = bpy.data.scenes.new("Elsewhere")
    elsewhere.frame_current = 6
    elsewhere.collection.objects.link(ob)
    for collection in list(ob.users_collection):
        if collection is not elsewhere.collection:
            collection.objects.unlink(ob)
    jobs.run_to_end(other)
    assert not timeline.catch_up()
    while timeline.drive_frames():
        pass
    np.testing.assert_allclose(positions_mm(ob), timeline.cache_for(ob).frames[6].positions, atol=1e-3)
    for collection in list(ob.users_collection):
        collection.objects.unlink(ob)
    scene.collection.objects.link(ob)
    # deleted while the job runs: let go
    other = jobs.start(export.export_job(ob, tmp_path / "gone.fold", scene=scene))
    jobs.run_slice(other, 0.0)
    scene.frame_set(7)
    assert timeline._missed
    jobs.run_to_end(other)
    bpy.data.objects.remove(ob)
    assert not timeline.catch_up() and not timeline._missed and not timeline.drive_frames()


def test_a_frame_that_does_not_converge_in_the_whole_budget_is_not_solved_again(folded, extension, monkeypatch):
    """A frame job solves with a bake's budget: a frame it leaves unconverged said "not converged in playback's
    12 iterations; Bake solves it fully" (false) and was solved again on every visit."""
    ob, _, _ = folded
    scene = bpy.context.scene
    timeline = mod(extension, "scene.timeline")
    jobs = mod(extension, "scene.jobs")
    keyframe_percent(ob, {1: 10.0, 9: 90.0})
    folding = mod(extension, "scene.folding")
    real = folding.solver_settings
    monkeypatch.setattr(folding, "solver_settings", lambda props, **kw: replace_iterations(real(props, **kw), 2))
    monkeypatch.setattr(timeline, "interactive", lambda: True)
    scene.frame_set(6)
    while timeline.drive_frames():
        pass
    entry = timeline.cache_for(ob).frames[6]
    assert not entry.converged and entry.full
    note = ob.curved_fold_mesh.last_message
    assert note.startswith("frame 6: not converged in the solver's whole budget (residual ") and "playback" not in note
    scene.frame_set(7)
    while timeline.drive_frames():
        pass
    scene.frame_set(6)  # shown from the cache: no job
    assert jobs.running_job(ob.name) is None


def replace_iterations(settings, n: int):
    settings.max_iterations = n
    return settings


def test_live_keeps_the_bake_marked_out_of_date(folded, extension):
    ob, _, crease = folded
    scene = bpy.context.scene
    live = mod(extension, "scene.live")
    bake = mod(extension, "scene.bake")
    scene.frame_start, scene.frame_end = 1, 4
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    keys_before = [k.name for k in ob.data.shape_keys.key_blocks]
    assert bpy.ops.curved_fold.toggle_live() == {"FINISHED"} and ob.curved_fold_mesh.live
    live.run_pending()  # turning Live on re-folds from the curves (unchanged: same mesh, no re-meshing)
    assert [k.name for k in ob.data.shape_keys.key_blocks] == keys_before  # the bake is kept
    # A settings-only live edit: re-solve without re-meshing, warm-started; the bake is kept, muted, out of date.
    faces, mesh_name = len(ob.data.polygons), ob.data.name
    ob.curved_fold_mesh.fold_percent = 50.0
    assert live._pending[ob.name][1] is False
    assert live.run_pending() == {ob.name: "ok"}
    assert len(ob.data.polygons) == faces and ob.data.name == mesh_name
    assert [k.name for k in ob.data.shape_keys.key_blocks] == keys_before
    assert bake.is_stale(ob) and all(k.mute for k in ob.data.shape_keys.key_blocks[1:])
    # A live curve edit re-meshes: the old mesh keeps the bake (fake user), the object gets the new mesh.
    crease.data.splines[0].bezier_points[1].handle_left = (0.08, 0.03, 0)
    live.schedule_refold(ob.name)
    assert live.run_pending() == {ob.name: "ok"}
    kept = bpy.data.meshes.get(ob[bake.STALE_MESH_KEY])
    assert kept is not None and kept.use_fake_user and kept is not ob.data
    assert [k.name for k in kept.shape_keys.key_blocks] == keys_before and bake.is_stale(ob)
    kept_name = kept.name
    # Re-bake: current again, the kept mesh is gone.
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    assert not bake.is_stale(ob) and bpy.data.meshes.get(kept_name) is None
    assert bake.baked_frames(ob) == [1, 2, 3, 4]
    ob.curved_fold_mesh.live = False
    live._pending.clear()


def _live_at_40(extension, ob):
    """Live on for ``ob``, its Fold Percent set to 40 with no edit pending: the live and jobs modules."""
    live = mod(extension, "scene.live")
    ob.curved_fold_mesh.live = True
    live._pending.clear()
    ob.curved_fold_mesh.fold_percent = 40.0
    return live, mod(extension, "scene.jobs")


def _live_off(live, ob) -> None:
    """Live off again and its timers removed (they never fire headless)."""
    ob.curved_fold_mesh.live = False
    for timer in (live._timer, live._drive):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)


def test_live_jobs_run_in_slices(folded, extension):
    """Interactive live re-folds run on a timer in slices (here driven by hand) and end with the re-fold done."""
    ob, _, _ = folded
    live, jobs = _live_at_40(extension, ob)
    assert live.run_pending(blocking=False) == {ob.name: "running"}
    assert jobs.running_job(ob.name) is not None
    slices = 1
    while live.drive_slices(budget_ms=0.0):
        slices += 1
    assert slices > 2 and jobs.running_job(ob.name) is None and ob.curved_fold_mesh.last_iterations > 0
    _live_off(live, ob)


def test_a_live_job_is_cancelled_by_its_cancel_button(folded, extension):
    """A live re-fold runs on a timer, with no modal handler to catch Esc (its progress row said "Esc cancels"): the
    row's Cancel button stops it, or any job on the object, and leaves the scene as it was."""
    ob, _, _ = folded
    live, jobs = _live_at_40(extension, ob)
    before = exact_state()
    assert live.run_pending(blocking=False) == {ob.name: "running"}
    job = jobs.running_job(ob.name)
    assert job is not None and job.live
    run_slices_until(jobs, job, "solve", then=1)
    assert exact_state() != before  # the preview moved the sheet
    assert bpy.ops.curved_fold.cancel_job(owner=ob.name) == {"FINISHED"}
    assert job.state == "cancelled" and exact_state() == before
    assert bpy.ops.curved_fold.cancel_job(owner=ob.name) == {"CANCELLED"}  # nothing running
    _live_off(live, ob)


def test_transfer_positions_carries_the_shape_onto_a_new_mesh(folded, extension):
    """The warm start of a live re-mesh: on the same mesh it is the identity; on a refined mesh, points on old
    triangles land on the old folded surface (a rigid motion of a flat sheet is reproduced exactly)."""
    ob, _, _ = folded
    transfer = mod(extension, "core.mesh.transfer")
    mesh = mod(extension, "scene.mesh_object").read_fold_mesh(ob)
    pos = positions_mm(ob)
    np.testing.assert_allclose(transfer.transfer_positions(mesh, pos, mesh), pos, atol=1e-9)
    # A flat sheet moved rigidly: every point of the sheet maps affinely, so interpolation is exact.
    rot = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    flat = np.c_[mesh.vertices, np.zeros(len(mesh.vertices))]
    moved = flat @ rot.T + [1.0, 2.0, 3.0]
    new = type(mesh)(**{**mesh.__dict__, "vertices": mesh.vertices * 0.98 + 1.0})
    got = transfer.transfer_positions(mesh, moved, new)
    expect = np.c_[new.vertices, np.zeros(len(new.vertices))] @ rot.T + [1.0, 2.0, 3.0]
    np.testing.assert_allclose(got, expect, atol=1e-6)


class _Event:
    def __init__(self, type_, value="NOTHING"):
        self.type, self.value = type_, value


def test_modal_loop_runs_slices_and_esc_cancels(folded, extension, monkeypatch):
    """The modal handler itself (``JobOperator.modal``, what a window timer drives), with events made here: timer
    ticks run slices to the end; other events pass through; Esc cancels with the scene as it was."""
    ob, _, _ = folded
    jobs = mod(extension, "scene.jobs")
    folding = mod(extension, "scene.folding")
    job_modal = mod(extension, "operators.job_modal")
    reports = []

    class Runner(job_modal.JobOperator):
        def report(self, kind, text):
            reports.append((next(iter(kind)), text))

        def done(self, context, result):
            reports.append(("DONE", result))

    monkeypatch.setattr(jobs, "SLICE_MS", 0.0)  # one unit per tick, so the small test job takes several
    ob.curved_fold_mesh.fold_percent = 40.0
    before = exact_state()
    runner = Runner()
    runner._job = jobs.start(folding.refold_job(ob, rebuild=False))
    assert runner.modal(bpy.context, _Event("MOUSEMOVE")) == {"PASS_THROUGH"}
    assert runner.modal(bpy.context, _Event("TIMER")) == {"RUNNING_MODAL"}
    assert runner.modal(bpy.context, _Event("ESC", "PRESS")) == {"CANCELLED"}
    assert runner._job.state == "cancelled" and exact_state() == before
    assert reports[-1][0] == "WARNING" and "as it was" in reports[-1][1]
    runner._job = jobs.start(folding.refold_job(ob, rebuild=False))
    ticks = 0
    while (state := runner.modal(bpy.context, _Event("TIMER"))) == {"RUNNING_MODAL"}:
        ticks += 1
    assert state == {"FINISHED"} and ticks >= 1 and reports[-1][0] == "DONE"
    assert reports[-1][1].report["percent"] == pytest.approx(0.4)


def test_a_slice_stops_before_a_unit_of_a_longer_kind():
    """A slice runs units while the next one fits the budget, predicted as the longest unit of its kind seen so far
    (the first of a kind: as long as the last unit). A bake alternates cheap warm iterations with long ones (a frame
    after a grid point), and predicting the next unit from the last let slices reach 110 ms of an 80 ms budget: here
    five short units ("a", 2 ms) then a long one ("b", 40 ms) with a 30 ms budget, where the old rule ran a slice of
    five a's and a b (50 ms)."""
    import time

    from curved_fold.scene import jobs

    current = [0]  # the slice running
    ran: list[tuple[int, str]] = []  # (slice, kind) of every unit

    def steps():
        for _ in range(4):  # a progress names the unit that follows it
            for i in range(5):
                ran.append((current[0], "a"))
                time.sleep(0.002)
                yield jobs.Progress("a" if i < 4 else "b")
            ran.append((current[0], "b"))
            time.sleep(0.040)
            yield jobs.Progress("a")
        return "done"

    job = jobs.start(jobs.Job("slicing-test", "test", steps()))
    while not jobs.run_slice(job, budget_ms=30.0):
        current[0] += 1
    assert job.result == "done"
    first_b = next(k for k, kind in ran if kind == "b")
    for k in range(first_b + 1, current[0] + 1):
        kinds = [kind for j, kind in ran if j == k]
        assert not ("a" in kinds and "b" in kinds[kinds.index("a") :]), (k, kinds)


def test_renaming_or_deleting_while_a_job_runs(folded, extension, monkeypatch):
    """A bake or fold of a big pattern takes seconds, and the user renames things in the Outliner meanwhile. Jobs
    found their objects by name: renaming the folded mesh during a bake, or a crease curve during a fold, raised a
    KeyError out of the modal operator (a traceback, the work lost, the timer and status text left behind). They
    now follow the renamed objects; one deleted under a running job ends it with one line and the scene as it was
    (the modal handler reports any other exception the same way)."""
    ob, border, crease = folded
    jobs = mod(extension, "scene.jobs")
    bake = mod(extension, "scene.bake")
    folding = mod(extension, "scene.folding")
    scene = bpy.context.scene
    job = jobs.start(bake.bake_job(ob, [1, 2, 3], scene=scene))
    run_slices_until(jobs, job, "frame")
    ob.name = "Paper Boat"
    summary = jobs.run_to_end(job)
    assert summary.ob_name == "Paper Boat" and len(bake.baked_frames(ob)) == 3
    job = jobs.start(folding.fold_job([border, crease], None, folding.FoldOptions(), scene=scene))
    run_slices_until(jobs, job, "solve")
    crease.name = "Valley S"
    made, _ = jobs.run_to_end(job)
    assert {s.object.name for s in made.curved_fold_mesh.sources} >= {"Valley S"}
    # deleted under a running re-fold: the modal handler ends it with one line, the scene as it was
    job_modal = mod(extension, "operators.job_modal")
    reports = []

    class Runner(job_modal.JobOperator):
        failure = "Re-fold failed"

        def report(self, kind, text):
            reports.append((next(iter(kind)), text))

    monkeypatch.setattr(jobs, "SLICE_MS", 0.0)
    runner = Runner()
    runner._job = jobs.start(folding.refold_job(made, rebuild=False))
    assert runner.modal(bpy.context, _Event("TIMER")) == {"RUNNING_MODAL"}
    name = made.name
    bpy.data.objects.remove(made)
    while (state := runner.modal(bpy.context, _Event("TIMER"))) == {"RUNNING_MODAL"}:
        pass
    assert state == {"CANCELLED"} and reports[-1][0] == "ERROR"
    assert (
        reports[-1][1] == f"Re-fold failed: the fold object '{name}' was deleted while the job ran; nothing was written"
    )


def test_a_bake_folds_keyed_settings_as_playback_does(folded, extension):
    """Crease stiffness keyed from 0.2 at frame 1 to 2.0 at frame 3, Fold Percent not keyed: playback folds each
    frame at the set percent with that frame's stiffness, and the bake must write the same shapes. It solved every
    frame with the stiffness of the frame Bake was pressed on and ramped the percent from 0 (a helper: frame 1 baked
    flat, played folded). Override Crease Angles' angle is part of the pattern and cannot be keyed (its keys did
    nothing)."""
    ob, _, _ = folded
    props = ob.curved_fold_mesh
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 3
    props.crease_stiffness = 0.2
    props.keyframe_insert("crease_stiffness", frame=1)
    props.crease_stiffness = 2.0
    props.keyframe_insert("crease_stiffness", frame=3)
    played = []
    for f in (1, 2, 3):
        scene.frame_set(f)
        played.append(evaluated_mm(ob))
    assert np.abs(played[0] - played[2]).max() > 1e-3  # the stiffness changes the shape
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    for f, shape in zip((1, 2, 3), played, strict=True):
        scene.frame_set(f)
        assert np.abs(evaluated_mm(ob) - shape).max() <= 1e-3 * np.ptp(shape, axis=0).max(), f
    assert not type(props).bl_rna.properties["fold_angle"].is_animatable


def test_an_import_runs_in_slices_and_esc_leaves_the_scene_as_it_was(extension, clean_scene, monkeypatch):
    """Importing CircularPleat-antiFacet (3,200 lines) took ~190 ms in one call, Blender frozen. The Import
    operator now runs a job: the file's elements a few hundred per unit, then each role's strokes chained, and only
    the commit makes the objects. Esc between slices leaves the scene exactly as it was; run to its end, the job
    makes what the one-call import makes."""
    from .conftest import FIXTURES

    jobs = mod(extension, "scene.jobs")
    import_curves = mod(extension, "scene.import_curves")
    job_modal = mod(extension, "operators.job_modal")
    path = str(FIXTURES / "origami-simulator" / "CircularPleat-antiFacet.svg")

    def scene_state():
        return (
            sorted(bpy.data.objects.keys()),
            sorted(bpy.data.curves.keys()),
            sorted(bpy.data.collections.keys()),
            sorted(bpy.data.materials.keys()),
        )

    before = scene_state()
    job = jobs.start(import_curves.import_job([path], scene=clean_scene))
    slices = 0
    while not jobs.run_slice(job, budget_ms=0.0):  # one unit per slice
        slices += 1
        assert scene_state() == before  # nothing written before the commit
        if slices == 8:
            assert job.progress.stage == "read" and "reading" in job.status()
            jobs.cancel(job)
            break
    assert job.state == "cancelled" and scene_state() == before
    job = jobs.start(import_curves.import_job([path], scene=clean_scene))
    units = 0
    while not jobs.run_slice(job, budget_ms=0.0):
        units += 1
    assert units >= 3200 // 250  # the elements a few hundred at a time, then the chains
    [(_, objects, _)], error = job.result
    assert error is None
    made = {ob.name: len(ob.data.splines) for ob in objects}
    for ob in objects:
        bpy.data.objects.remove(ob)
    one_call, _ = import_curves.import_crease_pattern(path, scene=clean_scene)
    assert {ob.name.split(".")[0]: len(ob.data.splines) for ob in one_call} == {
        name.split(".")[0]: n for name, n in made.items()
    }

    # Through the operator's modal handler: Esc cancels, timer ticks run the job to its end and select the objects.
    reports = []

    class Runner(job_modal.JobOperator):
        def report(self, kind, text):
            reports.append((next(iter(kind)), text))

        done = mod(extension, "operators.import_pattern").CURVED_FOLD_OT_import_pattern.done

    monkeypatch.setattr(jobs, "SLICE_MS", 0.0)
    before = scene_state()
    runner = Runner()
    runner._job = jobs.start(import_curves.import_job([path], scene=clean_scene))
    assert runner.modal(bpy.context, _Event("TIMER")) == {"RUNNING_MODAL"}
    assert runner.modal(bpy.context, _Event("ESC", "PRESS")) == {"CANCELLED"} and scene_state() == before
    runner._job = jobs.start(import_curves.import_job([path, path + ".missing.svg"], scene=clean_scene))
    while (state := runner.modal(bpy.context, _Event("TIMER"))) == {"RUNNING_MODAL"}:
        pass
    assert state == {"FINISHED"}  # the first file imported, the second reported
    assert [k for k, _ in reports].count("ERROR") == 1 and "Import failed" in reports[-1][1]
    assert len(bpy.context.selected_objects) == len(objects)


def test_undo_stops_running_jobs_first(folded, extension):
    """Ctrl+Z during a Re-fold or a Bake ended the job with "the scene changed while it ran (ReferenceError: StructRNA
    of type Scene has been removed)" (a designer session). Undo and redo now stop every running job first, as Esc
    does (its preview restored, the scene as it was), then take the scene back."""
    ob, _, _ = folded
    jobs = mod(extension, "scene.jobs")
    folding = mod(extension, "scene.folding")
    ob.curved_fold_mesh.fold_percent = 40.0
    before = exact_state()
    job = jobs.start(folding.refold_job(ob, rebuild=False))
    run_slices_until(jobs, job, "solve")
    for name in ("undo_pre", "redo_pre"):
        assert any(getattr(h, "__name__", "") == "on_undo" for h in getattr(bpy.app.handlers, name)), name
    handler = next(h for h in bpy.app.handlers.undo_pre if getattr(h, "__name__", "") == "on_undo")
    handler(bpy.context.scene)
    assert job.state == "cancelled" and exact_state() == before


def _baked_three_frames(extension):
    """The jobs, folding and bake modules and the scene, the active fold baked over frames 1–3."""
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 3
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    return mod(extension, "scene.jobs"), mod(extension, "scene.folding"), mod(extension, "scene.bake"), scene


def _bake_shown(jobs, steps):
    """A bake job started and run one unit per slice until its preview shows a frame."""
    job = jobs.start(steps)
    for _ in range(200):
        if job.shown is not None:
            return job
        assert not jobs.run_slice(job, budget_ms=0.0)
    raise AssertionError("the bake showed no frame")


def test_a_save_while_jobs_run_writes_the_scene_as_it_was(folded, extension, tmp_path):
    """Saved while a bake, a rebuild or a new fold runs, the file holds the scene as it was before them (the
    previews come off for the save and go back on after it, and the jobs go on). A designer session's Ctrl+S
    mid-rebuild saved the object pointing at the temporary mesh, and the bake's keys were lost on reopening;
    mid-bake the file held muted keys and a partial frame; mid-fold a stray half-folded mesh."""
    ob, border, crease = folded
    jobs, folding, bake, scene = _baked_three_frames(extension)
    edited, own, rebuild = _rebuild_shown(jobs, folding, ob, crease)
    fresh = jobs.start(folding.fold_job([border, crease], None, folding.FoldOptions(), scene=scene))
    run_slices_until(jobs, fresh, "solve", then=1)
    preview = positions_mm(ob).copy()
    path = str(tmp_path / "mid_job.blend")
    assert bpy.ops.wm.save_as_mainfile(filepath=path, copy=True) == {"FINISHED"}
    # the jobs go on, their previews back where they were
    assert rebuild.running and fresh.running and ob.data.name != own
    np.testing.assert_array_equal(positions_mm(ob), preview)
    assert fresh.owner == "Border Folded.001" and bpy.data.objects.get("Border Folded.001 (folding)") is not None
    jobs.cancel(rebuild)
    jobs.cancel(fresh)
    assert exact_state() == edited
    assert bpy.ops.wm.open_mainfile(filepath=path) == {"FINISHED"}
    assert exact_state() == edited
    # a bake saved mid-way: the file has the last bake's keys unmuted and the positions as they were
    ob = bpy.data.objects["Border Folded"]
    state = exact_state()
    job = _bake_shown(jobs, bake.bake_job(ob, [1, 2, 3], scene=bpy.context.scene))
    assert bpy.ops.wm.save_as_mainfile(filepath=path, copy=True) == {"FINISHED"}
    assert job.running
    jobs.cancel(job)
    assert exact_state() == state
    assert bpy.ops.wm.open_mainfile(filepath=path) == {"FINISHED"}
    assert exact_state() == state


def _edit(ob) -> None:
    bpy.context.view_layer.objects.active = ob
    assert bpy.ops.object.mode_set(mode="EDIT") == {"FINISHED"} and ob.mode == "EDIT"


def test_edit_mode_during_a_job_stops_it_and_leaves_the_object_as_it_was(folded, extension):
    """Tab into Edit Mode while a Bake ran: the next slice failed on the edit mesh ("the scene changed while it ran
    (KeyError: 'position')"), so did the preview's restore inside the error path, the job was never ended and every
    later Bake or Re-fold said the object was busy (a designer session). Now the job stops with one line, the object
    is taken out of Edit Mode and restored byte for byte, and is free for the next job; the same for a rebuild's
    preview mesh and for Esc pressed in Edit Mode."""
    ob, _, crease = folded
    jobs, folding, bake, scene = _baked_three_frames(extension)
    before = exact_state()
    job = _bake_shown(jobs, bake.bake_job(ob, [1, 2, 3], scene=scene))
    _edit(ob)
    with pytest.raises(jobs.EditModeError, match="'Border Folded' was put in Edit Mode while baking: stopped"):
        jobs.run_slice(job)
    assert job.state == "failed" and ob.mode == "OBJECT" and jobs.running_job(ob.name) is None
    assert exact_state() == before
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}  # not "busy"
    # saved while in Edit Mode: the save takes the preview off, and the job cannot go on
    before = exact_state()
    job = _bake_shown(jobs, bake.bake_job(ob, [1, 2, 3], scene=scene))
    _edit(ob)
    mod(extension, "scene.timeline").on_save_pre()
    assert job.state == "cancelled" and ob.mode == "OBJECT" and exact_state() == before
    # a rebuild shows a preview mesh on the object: Esc pressed in Edit Mode gives the object its own mesh back
    before, _, job = _rebuild_shown(jobs, folding, ob, crease)
    _edit(ob)
    jobs.cancel(job)
    assert job.state == "cancelled" and ob.mode == "OBJECT" and exact_state() == before


def test_edit_mode_during_a_live_re_fold_stops_it_with_a_message(folded, extension):
    """A live re-fold runs on a timer: Edit Mode under it stops it as it stops a modal job (the object back in Object
    Mode as it was), with the reason on the object, and the timer goes on for other live folds (an error out of the
    timer body would have stopped it)."""
    ob, _, _ = folded
    live, jobs = _live_at_40(extension, ob)
    before = exact_state()
    assert live.run_pending(blocking=False) == {ob.name: "running"}
    job = jobs.running_job(ob.name)
    run_slices_until(jobs, job, "solve", then=1)
    _edit(ob)
    assert live.drive_slices(budget_ms=0.0) is False  # no live job left, no exception out of the timer body
    assert job.state == "failed" and ob.mode == "OBJECT" and exact_state() == before
    assert ob.curved_fold_mesh.last_message.startswith("live re-fold failed: 'Border Folded' was put in Edit Mode")
    # any other failure under the timer (the scene changed) ends the job the same way, with no exception out of it
    ob.curved_fold_mesh.fold_percent = 50.0
    assert live.run_pending(blocking=False) == {ob.name: "running"}
    job = jobs.running_job(ob.name)

    def broken():
        yield jobs.Progress("solve")
        raise KeyError("position")

    job.steps = broken()
    assert live.drive_slices(budget_ms=0.0) is True  # the first unit
    assert live.drive_slices(budget_ms=0.0) is False and job.state == "failed"
    assert ob.curved_fold_mesh.last_message == (
        "live re-fold failed: the scene changed while it ran (KeyError: 'position')"
    )
    _live_off(live, ob)


def test_exports_and_frame_changes_work_on_a_fold_in_edit_mode(folded, extension, tmp_path):
    """In Edit Mode a mesh's arrays are empty: Export Mesh and Export SVG ended in a Python traceback, and every frame
    change of a keyframed fold printed one from its handler (a designer session). Exports now read the edit mesh, as
    Blender's own exporters do, and a fold being edited is not folded by frame changes."""
    ob, _, _ = folded
    timeline = mod(extension, "scene.timeline")
    keyframe_percent(ob, {1: 10.0, 9: 90.0})
    bpy.context.scene.frame_set(5)
    _edit(ob)
    for suffix in (".glb", ".fold", ".obj"):
        assert bpy.ops.curved_fold.export_folded(filepath=str(tmp_path / f"e{suffix}")) == {"FINISHED"}, suffix
        assert (tmp_path / f"e{suffix}").stat().st_size > 0
    assert bpy.ops.curved_fold.export_pattern_svg(filepath=str(tmp_path / "e.svg")) == {"FINISHED"}
    assert ob.mode == "EDIT"  # back where the user was
    for kind in ("STRAIN", "WARP", "CROSSING", "NONE"):
        assert bpy.ops.curved_fold.show_colours(kind=kind) == {"FINISHED"}, kind
    assert not timeline.driven(ob)
    bpy.context.scene.frame_set(8)  # no traceback from the handler; the edit mesh is the user's
    assert bpy.ops.object.mode_set(mode="OBJECT") == {"FINISHED"}
    assert timeline.driven(ob)


def test_a_fold_whose_commit_fails_leaves_nothing_behind(extension, clean_scene, monkeypatch):
    """The new fold object is written all or nothing, the record of its source curves included: a failure there
    (simulated) left the half-made object and its crease curves in the scene (a designer session)."""
    jobs = mod(extension, "scene.jobs")
    folding = mod(extension, "scene.folding")
    source_state = mod(extension, "scene.source_state")
    border, crease = curved_pattern()
    select_only([border, crease])
    before = exact_state()

    def fails(*_args, **_kw):
        raise MemoryError("simulated: out of memory")

    monkeypatch.setattr(source_state, "record", fails)
    job = jobs.start(folding.fold_job([border, crease], None, folding.FoldOptions(), scene=clean_scene))
    with pytest.raises(RuntimeError, match="writing the mesh failed: simulated: out of memory"):
        jobs.run_to_end(job)
    assert job.state == "failed" and exact_state() == before


def test_a_fold_whose_collection_is_deleted_while_it_runs_says_so(extension, clean_scene):
    """The collection the new fold goes into deleted while the fold ran: "writing the mesh failed: StructRNA of type
    Collection has been removed" (a designer session); now one line that says what happened, nothing written."""
    jobs = mod(extension, "scene.jobs")
    folding = mod(extension, "scene.folding")
    border, crease = curved_pattern()
    for then in (0, 3):  # before the preview is made, and after (the commit finds the collection gone)
        coll = bpy.data.collections.new("Pattern")
        clean_scene.collection.children.link(coll)
        for ob in (border, crease):
            coll.objects.link(ob)
            for other in list(ob.users_collection):
                if other != coll:
                    other.objects.unlink(ob)
        job = jobs.start(folding.fold_job([border, crease], coll, folding.FoldOptions(), scene=clean_scene))
        run_slices_until(jobs, job, "solve", then=then)
        assert (bpy.data.objects.get("Pattern Folded (folding)") is not None) == bool(then)
        for ob in (border, crease):
            clean_scene.collection.objects.link(ob)
        bpy.data.collections.remove(coll)
        with pytest.raises(RuntimeError, match="the collection 'Pattern' was deleted while the job ran; nothing was"):
            jobs.run_to_end(job)
        assert job.state == "failed" and not [ob for ob in bpy.data.objects if "Folded" in ob.name], then
