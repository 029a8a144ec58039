"""Nothing a user made is lost (issue 7, part 4).

* every operator that fails leaves the scene exactly as it was (datablocks, curve points, roles, mesh positions,
  attributes, shape keys: ``snapshot`` from tests/test_operators.py), for each catalogued kind of bad input;
* the user's crease curves are never modified by a fold, a re-fold, a bake or an export;
* a bake that fails keeps the previous bake (shape keys and keyframes) intact;
* files are written to a temporary name and moved into place: a failed write leaves the old file and no debris;
* the command line's outputs (issue 16): every format written whole or not at all (a write failing midway keeps
  the old file byte for byte), symlinks written through, devices/FIFOs/folders and input/output collisions
  refused, temporary files removed on SIGINT/SIGTERM, the report JSON finite, a progress line only on a terminal.
"""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from curved_fold.core.io.atomic import atomic_write_bytes, atomic_write_text  # noqa: E402

from .test_operators import curved_pattern, line, make_curve, mod, select_only, snapshot  # noqa: E402

pytestmark = pytest.mark.usefixtures("extension")


def curve_state(names=None) -> dict:
    """Exact control points (unrounded), role, angle, transform and spline flags of the curves named ``names``
    (default: every curve object). Fold objects add their own crease-display curves; they are not the user's."""
    out = {}
    for ob in bpy.data.objects:
        if ob.type != "CURVE" or (names is not None and ob.name not in names):
            continue
        pts = [
            (tuple(bp.co), tuple(bp.handle_left), tuple(bp.handle_right), bp.handle_left_type, bp.handle_right_type)
            for sp in ob.data.splines
            for bp in sp.bezier_points
        ]
        cyclic = [sp.use_cyclic_u for sp in ob.data.splines]
        out[ob.name] = (pts, cyclic, ob.curved_fold.role, ob.curved_fold.fold_angle, tuple(ob.matrix_world.col[3]))
    return out


def square_border(name="Border", w=100.0, h=60.0):
    c = [(0, 0), (w, 0), (w, h), (0, h)]
    return make_curve(name, [line(c[i], c[(i + 1) % 4]) for i in range(4)], "BORDER", closed=True)


# ------------------------------------------------------------------------------------------ nothing selected


def test_fold_with_nothing_selected(clean_scene):
    """Nothing selected: with no crease curve in the file the Fold operator is unavailable (poll says what to
    select); with crease curves in the file but none selected it says so by name. The scene is untouched."""
    assert not bpy.ops.curved_fold.fold.poll()
    curved_pattern()
    bpy.context.view_layer.update()
    for ob in bpy.context.view_layer.objects:
        ob.select_set(False)
    bpy.context.view_layer.objects.active = None
    before = snapshot()
    with pytest.raises(RuntimeError, match="no crease curves selected"):
        bpy.ops.curved_fold.fold()
    assert snapshot() == before


def test_empty_source_list_message(extension):
    common = mod(extension, "scene.folding")
    with pytest.raises(common.PatternError, match="no crease curves selected: select curve objects that have a"):
        common.pattern_from_objects([])


def test_fold_from_an_empty_collection_names_it(clean_scene):
    border, crease = curved_pattern()
    select_only([border, crease])  # the collection option overrides the selection
    coll = bpy.data.collections.new("Empty Creases")
    bpy.context.scene.collection.children.link(coll)
    before = snapshot()
    with pytest.raises(RuntimeError, match="no crease curves selected"):
        bpy.ops.curved_fold.fold(collection="Empty Creases")
    with pytest.raises(RuntimeError, match="no collection named 'Missing'"):
        bpy.ops.curved_fold.fold(collection="Missing")
    assert snapshot() == before


# ------------------------------------------------------------------------------------------ failing folds


def _self_crossing():
    pts = [(0, 0), (100, 60), (100, 0), (0, 60)]
    return [make_curve("Bowtie", [line(pts[i], pts[(i + 1) % 4]) for i in range(4)], "BORDER", closed=True)]


def _no_border():
    return [make_curve("Lonely", [line((0, 0), (100, 0))], "VALLEY", 90.0)]


def _degenerate_only():
    return [make_curve("Dot", [np.array([[5.0, 5.0]] * 4)], "MOUNTAIN", -90.0)]


def _absurd_scale():
    border = square_border()
    border.scale = (1e9, 1e9, 1.0)
    return [border]


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (_self_crossing, r"border crosses or touches itself .*Bowtie"),
        (_no_border, r"crease pattern has no border \(B\) segments"),
        (_degenerate_only, r"no crease curves selected"),  # a zero-length spline is not read as a curve
        (_absurd_scale, r"beyond ±1e\+08 mm"),
    ],
    ids=["self-crossing border", "no border", "degenerate curve only", "absurd scale"],
)
def test_failing_fold_leaves_scene_and_curves_unchanged(clean_scene, build, message):
    objects = build()
    bpy.context.view_layer.update()
    select_only(objects)
    before, curves = snapshot(), curve_state()
    with pytest.raises(RuntimeError, match=message):
        bpy.ops.curved_fold.fold()
    assert snapshot() == before
    assert curve_state() == curves


def test_pattern_that_cannot_fold_is_reported_and_curves_kept(clean_scene):
    """All mountains on concentric arcs (paper Fig. 7, examples/cannot_fold.svg imported as curves): the fold
    finishes in a stable state, says "does not fold as assigned", and the curves are exactly as they were."""
    path = Path(__file__).resolve().parents[1] / "examples" / "cannot_fold.svg"
    assert bpy.ops.curved_fold.import_pattern(filepath=str(path)) == {"FINISHED"}
    imported = list(bpy.context.selected_objects)
    select_only(imported)
    curves = curve_state()
    assert bpy.ops.curved_fold.fold() == {"FINISHED"}
    ob = bpy.context.active_object
    assert "does not fold as assigned" in ob.curved_fold_mesh.last_message
    co = np.empty(3 * len(ob.data.vertices))
    ob.data.vertices.foreach_get("co", co)
    assert np.all(np.isfinite(co))
    assert curve_state(set(curves)) == curves


# ------------------------------------------------------------------------------------------ successful runs


def test_fold_refold_bake_export_never_modify_curves(clean_scene, tmp_path):
    border, crease = curved_pattern()
    select_only([border, crease])
    curves = curve_state()
    mine = set(curves)
    assert bpy.ops.curved_fold.fold() == {"FINISHED"}
    ob = bpy.context.active_object
    assert curve_state(mine) == curves
    ob.curved_fold_mesh.fold_percent = 60.0
    assert bpy.ops.curved_fold.refold() == {"FINISHED"}
    assert curve_state(mine) == curves
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 3
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    assert curve_state(mine) == curves
    out = tmp_path / "folded.glb"
    assert bpy.ops.curved_fold.export_folded(filepath=str(out), file_format="GLB") == {"FINISHED"}
    assert out.is_file() and curve_state(mine) == curves
    assert [p.name for p in tmp_path.iterdir()] == ["folded.glb"]  # no temporary file left behind


def test_failing_bake_keeps_the_previous_bake(clean_scene):
    """A bake that fails (the fold mesh was edited into quads after folding) keeps the shape keys and keyframes of
    the previous bake, the mesh and the curves exactly as they were."""
    import bmesh

    border, crease = curved_pattern()
    select_only([border, crease])
    assert bpy.ops.curved_fold.fold() == {"FINISHED"}
    ob = bpy.context.active_object
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 3
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    keys = [k.name for k in ob.data.shape_keys.key_blocks]
    assert len(keys) >= 3
    # damage: join two triangles into a quad (as a user editing the folded mesh would)
    bm = bmesh.new()
    bm.from_mesh(ob.data)
    interior = next(e for e in bm.edges if len(e.link_faces) == 2)
    bmesh.ops.dissolve_edges(bm, edges=[interior])
    bm.to_mesh(ob.data)
    bm.free()
    ob.data.update()
    before, curves = snapshot(), curve_state()
    with pytest.raises(RuntimeError, match="non-triangle faces"):
        bpy.ops.curved_fold.bake()
    assert snapshot() == before
    assert [k.name for k in ob.data.shape_keys.key_blocks] == keys
    assert curve_state() == curves


# ------------------------------------------------------------------------------------------ imports and exports


@pytest.mark.parametrize(
    ("name", "data", "message"),
    [
        ("broken.svg", "<svg><path></svg>", r"malformed XML at line 1"),
        (
            "colours.svg",
            '<svg xmlns="http://www.w3.org/2000/svg"><path d="M0 0 L1 1" stroke="#123456"/></svg>',
            "no usable",
        ),
        (
            "arrays.fold",
            '{"vertices_coords": [[0, 0]], "edges_vertices": [[0, 3]], "edges_assignment": ["B"]}',
            r"edges_vertices\[0\] = \[0, 3\]: index 3 out of range",
        ),
        ("empty.fold", "", r"malformed JSON at line 1, column 1"),
        # issue 16: these two reached the Import operator as raw tracebacks (StopIteration, TypeError)
        (
            "empty_coords.fold",
            '{"vertices_coords": [[], []], "edges_vertices": [[0, 1]], "edges_assignment": ["B"]}',
            r"vertices_coords\[0\] = \[\]: a vertex needs 2 or 3 coordinates",
        ),
        (
            "sources.fold",
            '{"vertices_coords": [[0, 0], [1, 0]], "edges_vertices": [[0, 1]], "edges_assignment": ["B"], '
            '"curved_fold:sources": 5, "curved_fold:edge_polyline": [0]}',
            r"curved_fold:sources = 5 must be an array",
        ),
        ("nested.svg", '<svg xmlns="http://www.w3.org/2000/svg">' + "<g>" * 1000 + "</g>" * 1000 + "</svg>", "nesting"),
    ],
)
def test_failing_import_leaves_scene_unchanged(clean_scene, tmp_path, name, data, message):
    curved_pattern()
    before = snapshot()
    path = tmp_path / name
    path.write_text(data)
    with pytest.raises(RuntimeError, match=message):
        bpy.ops.curved_fold.import_pattern(filepath=str(path))
    assert snapshot() == before


def test_failing_export_leaves_scene_and_old_file(clean_scene, tmp_path):
    border, crease = curved_pattern()
    select_only([border, crease])
    assert bpy.ops.curved_fold.fold() == {"FINISHED"}
    before = snapshot()
    with pytest.raises(RuntimeError, match="failed"):
        bpy.ops.curved_fold.export_folded(filepath=str(tmp_path / "missing" / "out.fold"), file_format="FOLD")
    assert snapshot() == before
    assert not (tmp_path / "missing").exists()


def test_atomic_write_replaces_whole_file_or_nothing(tmp_path):
    dest = tmp_path / "pattern.fold"
    atomic_write_text(dest, "old contents")
    atomic_write_text(dest, "new contents")
    assert dest.read_text() == "new contents"
    # a destination that cannot be replaced (a non-empty directory of that name): error, nothing left behind
    blocked = tmp_path / "blocked.fold"
    blocked.mkdir()
    (blocked / "keep.txt").write_text("x")
    with pytest.raises(OSError):
        atomic_write_bytes(blocked, b"data")
    assert (blocked / "keep.txt").read_text() == "x"
    # a write interrupted half-way (data that cannot be encoded) leaves the old file untouched
    with pytest.raises(UnicodeEncodeError):
        atomic_write_text(dest, "caf\udce9")
    assert dest.read_text() == "new contents"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocked.fold", "pattern.fold"]


def test_atomic_write_into_missing_folder(tmp_path):
    with pytest.raises(OSError):
        atomic_write_text(tmp_path / "nope" / "x.svg", "<svg/>")
    assert list(tmp_path.iterdir()) == []
    assert not any(name.endswith(".tmp") for name in os.listdir(tmp_path))


def test_export_overwrite_is_atomic(clean_scene, tmp_path):
    """Exporting over an existing file replaces it in one move: the old file is never half-written."""
    border, crease = curved_pattern()
    select_only([border, crease])
    assert bpy.ops.curved_fold.fold() == {"FINISHED"}
    out = tmp_path / "out.fold"
    out.write_text("previous export")
    inode = out.stat().st_ino
    assert bpy.ops.curved_fold.export_folded(filepath=str(out), file_format="FOLD") == {"FINISHED"}
    assert out.read_text().lstrip().startswith("{") and out.stat().st_ino != inode  # a new file moved into place
    assert sorted(p.name for p in Path(tmp_path).iterdir()) == ["out.fold"]


# ------------------------------------------------------------------------------------------ outputs (issue 16)

SIMPLE = Path(__file__).resolve().parent / "fixtures" / "origami-simulator" / "simpleVertex.svg"
OLD_BYTES = b"old file \x00\x01 kept byte for byte\n"


def _cli_with_file_size_limit(args: list[str], limit: int) -> subprocess.CompletedProcess:
    """Run ``python -m curved_fold`` with writes above ``limit`` bytes failing (EFBIG, as a full disk would), the
    way ``ulimit -f`` does it; SIGXFSZ is ignored so the write fails instead of killing the process."""

    def limit_writes() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return subprocess.run(
        [sys.executable, "-m", "curved_fold", *args],
        preexec_fn=limit_writes,
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.mark.parametrize("suffix", [".fold", ".obj", ".glb", ".blend"])
def test_output_failing_midway_keeps_the_old_file(tmp_path, suffix):
    """Every output format: a write cut off after 1,500 bytes (the file-size limit stands in for a full disk) ends
    with exit 2 and one line naming the user's path, the old file byte for byte, and no temporary file. Before,
    a cut ``.obj`` replaced the old one and Blender said "File exported successfully" (exit 0)."""
    out = tmp_path / f"folded{suffix}"
    out.write_bytes(OLD_BYTES)
    r = _cli_with_file_size_limit(["fold", str(SIMPLE), "--out", str(out), "--quiet"], 1500)
    assert r.returncode == 2, r.stderr
    last = r.stderr.strip().splitlines()[-1]
    assert last.startswith("curved_fold: error: ") and str(out) in last and ".tmp" not in last, r.stderr
    assert "Traceback" not in r.stderr
    assert out.read_bytes() == OLD_BYTES
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]


@pytest.mark.parametrize("suffix", [".fold", ".obj", ".glb", ".blend"])
def test_output_written_whole_through_the_command_line(tmp_path, suffix):
    """The same run without a limit replaces the old file with a whole one (the completeness check passes)."""
    from curved_fold.cli import main

    out = tmp_path / f"folded{suffix}"
    out.write_bytes(OLD_BYTES)
    assert main(["fold", str(SIMPLE), "--out", str(out), "--quiet"]) == 0
    data = out.read_bytes()
    assert data != OLD_BYTES and len(data) > 1000
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]


def test_failing_report_leaves_the_mesh_unwritten(tmp_path, monkeypatch, capsys):
    """Mesh and report are written together: a report that fails leaves the old mesh (before, exit 2 came after
    the mesh had been replaced)."""
    import curved_fold.cli.fold as cli_fold
    from curved_fold.cli import main

    out, report = tmp_path / "folded.fold", tmp_path / "report.json"
    out.write_bytes(OLD_BYTES)

    def disk_full(value):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(cli_fold, "finite_json", disk_full)
    assert main(["fold", str(SIMPLE), "--out", str(out), "--report", str(report)]) == 2
    assert "No space left on device" in capsys.readouterr().err
    assert out.read_bytes() == OLD_BYTES and not report.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]


def test_out_through_a_symlink_writes_its_target(tmp_path):
    from curved_fold.cli import main

    target = tmp_path / "real.fold"
    target.write_bytes(OLD_BYTES)
    link = tmp_path / "link.fold"
    link.symlink_to(target.name)
    assert main(["fold", str(SIMPLE), "--out", str(link), "--quiet"]) == 0
    assert link.is_symlink() and os.readlink(link) == target.name
    assert target.read_bytes().lstrip().startswith(b"{")
    assert oct(target.stat().st_mode & 0o777) != oct(0o600)  # not the temporary file's private mode
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.fold", "real.fold"]


@pytest.mark.parametrize("kind", ["device", "fifo", "folder"])
def test_non_regular_out_is_refused(tmp_path, capsys, kind):
    from curved_fold.cli import main

    out = tmp_path / "o.fold"
    if kind == "device":
        out.symlink_to("/dev/null")
    elif kind == "fifo":
        os.mkfifo(out)
    else:
        out.mkdir()
    before = os.stat(out).st_mode
    assert main(["fold", str(SIMPLE), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"--out {out}: is a" in err and "not a regular file; refusing to write there" in err
    assert os.stat(out).st_mode == before and oct(os.stat("/dev/null").st_mode)[:4] == "0o20"  # still a device


@pytest.mark.parametrize(
    ("which", "message"),
    [
        ("out=input", r"--out .*: is the input file"),
        ("report=out", r"--out .* and --report .* name the same file"),
        ("report=input", r"--report .*: is the input file"),
    ],
)
def test_output_collisions_are_refused(tmp_path, capsys, which, message):
    import re

    from curved_fold.cli import main

    src = tmp_path / "pattern.fold"
    assert main(["discretize", str(SIMPLE), "--out", str(src), "--quiet"]) == 0
    original = src.read_bytes()
    out, report = tmp_path / "folded.fold", tmp_path / "r.json"
    if which == "out=input":
        out = tmp_path / "." / "pattern.fold"
    elif which == "report=out":
        report = out
    else:
        report = tmp_path / "link.json"
        report.symlink_to(src)
    assert main(["fold", str(src), "--out", str(out), "--report", str(report)]) == 2
    assert re.search(message, capsys.readouterr().err)
    assert src.read_bytes() == original


SIGNAL_WRITER = r"""
import os, sys, time
from curved_fold.core.io.atomic import atomic_output, install_signal_cleanup
install_signal_cleanup()
try:
    with atomic_output(sys.argv[1]) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(b"half a file")
            fh.flush()
        print(tmp, flush=True)
        time.sleep(60)
except KeyboardInterrupt:
    sys.exit(130)
"""


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_signal_during_a_write_removes_the_temporary_file(tmp_path, signum):
    out = tmp_path / "out.fold"
    out.write_bytes(OLD_BYTES)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.Popen([sys.executable, "-c", SIGNAL_WRITER, str(out)], stdout=subprocess.PIPE, text=True, env=env)
    tmp = proc.stdout.readline().strip()
    assert Path(tmp).exists() and Path(tmp).parent == tmp_path
    proc.send_signal(signum)
    assert proc.wait(timeout=30) == (143 if signum == signal.SIGTERM else 130)
    assert not Path(tmp).exists()
    assert out.read_bytes() == OLD_BYTES
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.fold"]


def test_temporary_files_of_a_killed_run_are_swept_by_the_next_write(tmp_path):
    """SIGKILL leaves no chance to clean up: the killed run's temporary file (and the one a Blender exporter writes
    inside it) stayed in the user's folder for good. The next write to the same file removes those of processes
    that are gone, and leaves a write in progress (a live process's) alone."""
    out = tmp_path / "out.fold"
    out.write_bytes(OLD_BYTES)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.Popen([sys.executable, "-c", SIGNAL_WRITER, str(out)], stdout=subprocess.PIPE, text=True, env=env)
    tmp = Path(proc.stdout.readline().strip())
    inner = tmp.parent / f".{tmp.stem}.cf{proc.pid}-abc123.tmp.fold"  # an exporter's own temporary file
    inner.write_bytes(b"x")
    proc.kill()
    proc.wait(timeout=30)
    assert tmp.exists() and out.read_bytes() == OLD_BYTES
    live = tmp_path / f".out.cf{os.getpid()}-live.tmp.fold"
    live.write_bytes(b"in progress")
    other = tmp_path / ".other.cf999999999-x.tmp.fold"  # another file's: not this write's business
    other.write_bytes(b"x")
    atomic_write_text(out, "new")
    assert out.read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["out.fold", live.name, other.name])


def test_report_json_has_no_infinity(tmp_path):
    import json

    from curved_fold.cli import main
    from curved_fold.cli.outputs import finite_json

    assert finite_json({"a": float("inf"), "b": [1.0, float("nan")], "c": np.float64(-np.inf), "d": 2}) == {
        "a": None,
        "b": [1.0, None],
        "c": None,
        "d": 2,
    }
    report = tmp_path / "r.json"
    assert main(["fold", str(SIMPLE), "--out", str(tmp_path / "o.fold"), "--report", str(report), "-q"]) == 0
    text = report.read_text()
    assert "Infinity" not in text and "NaN" not in text
    json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in the report"))


def test_progress_line_only_on_a_terminal_and_not_quiet():
    import io
    import time

    from curved_fold.cli.progress import Progress

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    tty, pipe = Terminal(), io.StringIO()
    for progress in (Progress(stream=tty), Progress(stream=pipe), Progress(stream=Terminal(), quiet=True)):
        with progress.stage("meshing"):
            time.sleep(2.0)
    assert "\rcurved_fold: meshing... 1 s\033[K" in tty.getvalue() and tty.getvalue().endswith("\r\033[K")
    assert pipe.getvalue() == ""
    quick = Terminal()
    with Progress(stream=quick).stage("solving"):
        time.sleep(0.2)
    assert quick.getvalue() == ""  # under a second: nothing drawn


def test_sigterm_during_a_command_line_fold(tmp_path):
    """SIGTERM while ``fold`` works (reading, meshing, solving or writing) ends with status 143, one line, the old
    output byte for byte and no temporary file (Linux: the handler is detected through /proc)."""
    import time

    out = tmp_path / "folded.glb"
    out.write_bytes(OLD_BYTES)
    src = SIMPLE.parent / "Treble_Clef.svg"
    proc = subprocess.Popen(
        [sys.executable, "-m", "curved_fold", "fold", str(src), "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    # wait until the command line has installed its handler (SigCgt in /proc has the SIGTERM bit), then let it work
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        with open(f"/proc/{proc.pid}/status") as fh:
            caught = int(next(x for x in fh if x.startswith("SigCgt:")).split()[1], 16)
        if caught & (1 << (signal.SIGTERM - 1)):
            break
        time.sleep(0.05)
    time.sleep(0.5)
    proc.terminate()
    _, err = proc.communicate(timeout=60)
    if proc.returncode == 0:  # finished before the signal on a fast machine: nothing to check but the result
        assert out.read_bytes() != OLD_BYTES
    else:
        assert proc.returncode == 143, err
        assert err.strip().splitlines()[-1] == "curved_fold: terminated (unfinished temporary files removed)"
        assert out.read_bytes() == OLD_BYTES
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]


def test_signals_while_blender_loads_are_held_then_acted_on():
    """``bpy`` registers its bundled add-ons inside error handlers: a Ctrl+C raised in there was swallowed (the run
    went on and replaced the output file) or left Blender half set up (a segmentation fault at exit; a CLI review
    session). While it loads, SIGINT and SIGTERM are held; after, they act as the handlers in force would have."""
    from curved_fold.core.io.atomic import signals_held

    def terminate(signum, _frame):
        raise SystemExit(128 + signum)

    done = []
    previous = signal.signal(signal.SIGINT, signal.default_int_handler), signal.signal(signal.SIGTERM, terminate)
    try:
        with pytest.raises(KeyboardInterrupt):
            with signals_held():
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)  # delivered here: held
                done.append("loaded")
        with pytest.raises(SystemExit) as stopped:
            with signals_held():
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(0.05)
                done.append("loaded again")
        assert stopped.value.code == 143 and done == ["loaded", "loaded again"]
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        assert signal.getsignal(signal.SIGTERM) is terminate
    finally:
        signal.signal(signal.SIGINT, previous[0])
        signal.signal(signal.SIGTERM, previous[1])


def test_a_write_error_that_names_no_file_names_the_users_path(tmp_path):
    """A full disk during ``write()`` raises an OSError that names no file: the report's message said only
    "[Errno 28] No space left on device" (a CLI review session). It names the user's path now."""
    import errno

    from curved_fold.core.io.atomic import atomic_output

    out = tmp_path / "r.json"
    with pytest.raises(OSError) as failed:
        with atomic_output(out):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    assert str(failed.value) == f"[Errno 28] No space left on device: '{out}'"
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_command_line_restores_the_signal_handlers(tmp_path):
    from curved_fold.cli import main

    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    assert main(["discretize", str(SIMPLE), "--out", str(tmp_path / "p.fold"), "-q"]) == 0
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before


def test_progress_line_names_the_engine_step(monkeypatch):
    """During a real fold longer than the line's delay the line says which step runs (read from the working thread).
    The delay is shortened to 0.05 s: Treble_Clef now folds in about a second, sometimes just under the real one."""
    import io

    from curved_fold.cli import progress as progress_module
    from curved_fold.cli.progress import Progress

    monkeypatch.setattr(progress_module, "DELAY_S", 0.05)
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.pipeline import fold_pattern

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    tty = Terminal()
    pattern = read_pattern(SIMPLE.parent / "Treble_Clef.svg")
    progress = Progress(stream=tty)
    with progress.stage("folding"):
        fold_pattern(pattern, angle=90)
    lines = tty.getvalue().split("\r")
    assert progress.drawn > 0
    assert any(x.startswith(("curved_fold: folding: meshing", "curved_fold: folding: solving")) for x in lines), lines
