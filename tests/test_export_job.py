"""Export Folded Mesh as a job, headless: timers and modal loops do not run here, so the slice function is driven
directly (as in ``test_jobs.py``) and the operator runs through ``bpy.ops`` (EXEC_DEFAULT, the blocking path).

A real pattern (wavy_pleats, imported, folded and baked over six frames through the operators):

* the job run in slices writes the file the blocking operator writes, byte for byte (GLB, OBJ, STL, FOLD; a .blend
  holds memory addresses that differ from run to run, so it is read back instead);
* one frame per unit and Blender's exporter in a slice of its own;
* cancelled mid-export, no file and no temporary file is left, an existing target keeps its bytes and the scene is
  exactly as it was (the temporary export scene removed);
* a second job on the object is refused with the one-line "busy" error; a save cancels a job holding its
  temporary scene.
"""

from __future__ import annotations

import pytest

bpy = pytest.importorskip("bpy")

from .test_jobs import exact_state  # noqa: E402
from .test_operators import mod, select_only  # noqa: E402

pytestmark = pytest.mark.usefixtures("extension")

FRAMES = 6
FORMATS = {"FOLD": ".fold", "GLB": ".glb", "OBJ": ".obj", "STL": ".stl", "BLEND": ".blend"}


@pytest.fixture
def baked(extension, clean_scene, fixtures_dir):
    """wavy_pleats imported, folded and baked over frames 1–6; the folded object active."""
    svg = fixtures_dir / "origami-simulator" / "wavy_pleats.svg"
    assert bpy.ops.curved_fold.import_pattern(filepath=str(svg)) == {"FINISHED"}
    select_only(list(bpy.context.selected_objects))
    assert bpy.ops.curved_fold.fold() == {"FINISHED"}
    ob = bpy.context.active_object
    clean_scene.frame_start, clean_scene.frame_end = 1, FRAMES
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    assert len(mod(extension, "scene.bake").baked_frames(ob)) == FRAMES
    return ob


def datablocks() -> dict[str, list[str]]:
    """Names of the datablocks an export's temporary scene makes."""
    kinds = ("scenes", "objects", "meshes", "curves", "actions", "materials", "shape_keys")
    return {kind: sorted(d.name for d in getattr(bpy.data, kind)) for kind in kinds}


def run_sliced(jobs, job, monkeypatch, export) -> dict:
    """Run ``job`` one unit per slice (a zero budget) to its end; what each slice did: the frame reached per slice,
    and at which unit of its slice Blender's exporter was called."""
    calls = []
    run_exporter = export._run_exporter

    def recording(*args, **kwargs):
        calls.append((job.slices, job.units))
        return run_exporter(*args, **kwargs)

    monkeypatch.setattr(export, "_run_exporter", recording)
    starts, frames = {}, []
    for _ in range(500):
        starts[job.slices] = job.units
        ended = jobs.run_slice(job, budget_ms=0.0)
        frames.append((job.progress.stage, job.progress.frame))
        if ended:
            break
    assert job.state == "done", job.error
    return {"starts": starts, "frames": frames, "exporter": calls}


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_an_export_in_slices_writes_the_blocking_file(baked, extension, tmp_path, monkeypatch, fmt):
    jobs, export = mod(extension, "scene.jobs"), mod(extension, "scene.export")
    suffix = FORMATS[fmt]
    blocking, sliced = tmp_path / f"blocking{suffix}", tmp_path / f"sliced{suffix}"
    assert bpy.ops.curved_fold.export_folded(filepath=str(blocking), file_format=fmt) == {"FINISHED"}
    before = exact_state()
    job = jobs.start(export.export_job(baked, sliced, scene=bpy.context.scene))
    done = run_sliced(jobs, job, monkeypatch, export)
    assert exact_state() == before and jobs.running_job(baked.name) is None
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([blocking.name, sliced.name])  # no temporary file
    result = job.result
    assert result.path == sliced and result.baked and result.n_frames == (1 if suffix in (".obj", ".stl") else FRAMES)
    # one unit a slice (zero budget): the frames are read (FOLD: and measured, then encoded) one per unit
    n = result.n_frames
    read = [f for stage, f in done["frames"] if stage == "frame"]
    assert read == list(range(1, n + 1)), done["frames"]
    if suffix == ".fold":
        encoded = [f for stage, f in done["frames"] if stage == "encode"]
        assert encoded == list(range(n + 1)) and job.units >= 2 * n + 1
        assert done["exporter"] == []
        assert blocking.read_bytes() == sliced.read_bytes()
        return
    # Blender's exporter: called once, as the first unit of its slice (nothing else added to that slice)
    assert len(done["exporter"]) == 1
    slice_index, units = done["exporter"][0]
    assert units == done["starts"][slice_index]
    if suffix == ".blend":  # pointers differ from run to run: compare what the files hold
        assert abs(blocking.stat().st_size - sliced.stat().st_size) <= 64
        for path in (blocking, sliced):
            with bpy.data.libraries.load(str(path)) as (src, _):
                assert baked.name in src.objects and len(src.meshes) == 1
    else:
        assert blocking.read_bytes() == sliced.read_bytes()


def test_slices_keep_near_the_budget_but_for_the_exporter(baked, extension, tmp_path):
    """At the default budget the per-frame work shares slices, and the exporter's slice holds no other unit: a FOLD
    export of 6 frames is ≥ 14 units (the pattern, 6 frames read, the key frame and 6 frames encoded, the write)."""
    jobs, export = mod(extension, "scene.jobs"), mod(extension, "scene.export")
    job = jobs.start(export.export_job(baked, tmp_path / "a.fold"))
    jobs.run_to_end(job)
    assert job.units >= 2 * FRAMES + 2 and set(job.unit_ms) >= {"start", "frame", "encode", "write"}
    job = jobs.start(export.export_job(baked, tmp_path / "a.glb"))
    jobs.run_to_end(job)
    assert {"start", "frame", "setup", "export"} <= set(job.unit_ms)


@pytest.mark.parametrize("fmt", ["FOLD", "GLB", "BLEND"])
@pytest.mark.parametrize("existing", [False, True])
def test_cancel_mid_export_leaves_files_and_scene_as_they_were(baked, extension, tmp_path, fmt, existing):
    jobs, export = mod(extension, "scene.jobs"), mod(extension, "scene.export")
    target = tmp_path / f"out{FORMATS[fmt]}"
    if existing:
        target.write_bytes(b"the user's old file\n")
    files = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    before, blocks = exact_state(), datablocks()
    job = jobs.start(export.export_job(baked, target))
    for _ in range(100):  # into the file-writing half: FOLD frames encoded, the temporary scene made
        assert not jobs.run_slice(job, budget_ms=0.0)
        if job.progress.stage == "encode" and job.progress.frame >= 2 or job.preview.holds_datablocks:
            break
    if fmt != "FOLD":
        assert datablocks() != blocks
    assert "Esc" not in job.status() and "exporting" in job.status()
    jobs.cancel(job)
    assert job.state == "cancelled" and jobs.running_job(baked.name) is None
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == files
    assert exact_state() == before and datablocks() == blocks
    assert bpy.context.window is None or bpy.context.window.scene == bpy.context.scene


def test_a_second_job_on_the_object_is_busy_and_a_save_cancels_the_export(baked, extension, tmp_path):
    jobs, export = mod(extension, "scene.jobs"), mod(extension, "scene.export")
    job = jobs.start(export.export_job(baked, tmp_path / "a.glb"))
    for _ in range(100):
        assert not jobs.run_slice(job, budget_ms=0.0)
        if job.preview.holds_datablocks:
            break
    with pytest.raises(RuntimeError, match=r"Export of '.*' failed: '.*' is busy \(exporting\)"):
        bpy.ops.curved_fold.export_folded(filepath=str(tmp_path / "b.glb"), file_format="GLB")
    with pytest.raises(RuntimeError, match="busy"):
        bpy.ops.curved_fold.bake()
    blocks = datablocks()
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "saved.blend"), copy=True)  # without the temporary scene
    assert job.state == "cancelled" and "saved" in job.cancel_reason and datablocks() != blocks
    with bpy.data.libraries.load(str(tmp_path / "saved.blend")) as (src, _):
        assert list(src.scenes) == [bpy.context.scene.name]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["saved.blend"]


def test_an_export_stops_if_its_object_is_put_in_edit_mode(baked, extension, tmp_path):
    jobs, export = mod(extension, "scene.jobs"), mod(extension, "scene.export")
    before = datablocks()
    job = jobs.start(export.export_job(baked, tmp_path / "a.fold"))
    assert not jobs.run_slice(job, budget_ms=0.0)
    bpy.ops.object.mode_set(mode="EDIT")
    with pytest.raises(jobs.EditModeError, match="Edit Mode while exporting"):
        jobs.run_slice(job, budget_ms=0.0)
    assert baked.mode == "OBJECT" and datablocks() == before and list(tmp_path.iterdir()) == []


def test_the_modal_export_ends_with_its_own_error_or_esc(baked, extension, tmp_path, monkeypatch):
    """The modal handler driven by hand (timer ticks, Esc): a write that fails (a missing folder) ends the job with
    its own message, not "the scene changed while it ran"; Esc leaves no file; a save cancelling it is reported."""
    from .test_jobs import _Event

    jobs, export = mod(extension, "scene.jobs"), mod(extension, "scene.export")
    job_modal = mod(extension, "operators.job_modal")
    reports = []

    class Runner(job_modal.JobOperator):
        own_errors = (OSError,)
        failure = "Export failed"

        def report(self, kind, text):
            reports.append((next(iter(kind)), text))

    monkeypatch.setattr(jobs, "SLICE_MS", 0.0)
    runner = Runner()
    runner._job = jobs.start(export.export_job(baked, tmp_path / "missing" / "a.fold"))
    while (state := runner.modal(bpy.context, _Event("TIMER"))) == {"RUNNING_MODAL"}:
        pass
    assert state == {"CANCELLED"} and reports[-1][0] == "ERROR", reports
    assert "does not exist" in reports[-1][1] and "scene changed" not in reports[-1][1]
    runner._job = jobs.start(export.export_job(baked, tmp_path / "a.glb"))
    for _ in range(FRAMES + 2):
        assert runner.modal(bpy.context, _Event("TIMER")) == {"RUNNING_MODAL"}
    assert runner.modal(bpy.context, _Event("ESC", "PRESS")) == {"CANCELLED"}
    assert "as it was" in reports[-1][1] and list(tmp_path.iterdir()) == []
    # a save (its handler hides the previews) cancels an export holding its temporary scene: the operator says so
    runner._job = jobs.start(export.export_job(baked, tmp_path / "a.glb"))
    while not runner._job.preview.holds_datablocks:
        assert runner.modal(bpy.context, _Event("TIMER")) == {"RUNNING_MODAL"}
    jobs.hide_previews()
    assert runner.modal(bpy.context, _Event("TIMER")) == {"CANCELLED"}
    assert reports[-1][0] == "WARNING" and "saved" in reports[-1][1] and list(tmp_path.iterdir()) == []
