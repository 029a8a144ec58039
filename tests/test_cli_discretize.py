"""The ``discretize`` subcommand, run as a real subprocess."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
REPO = Path(__file__).resolve().parents[1]


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "curved_fold", "discretize", *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=REPO,
        # Python's environment, not the process's: bpy 5.2 setenv()s OCIO when imported (by earlier tests), and a
        # child bpy 5.2 started with OCIO set logs "color_management | Using OCIO=..." on import
        env=dict(os.environ),
    )


def test_discretize_wavy_pleats(tmp_path: Path) -> None:
    out = tmp_path / "w.fold"
    res = run(str(FIXTURES / "wavy_pleats.svg"), "--out", str(out))
    assert res.returncode == 0, res.stderr
    text = res.stdout
    assert "interval: 5.25 mm (default, scale-aware)" in text  # 425.2 px border = 112.5 mm → 7 × 112.5 / 150
    assert "tolerance: 0.0525 mm (default, scale-aware)" in text
    assert "merge tolerance: 0.0375 mm (default, scale-aware)" in text
    data = json.loads(out.read_text())
    n_v, n_e = len(data["vertices_coords"]), len(data["edges_vertices"])
    assert f"vertices: {n_v}" in text and f"segments: {n_e} (" in text
    counts = {a: data["edges_assignment"].count(a) for a in "BMVFUC"}
    assert f"B {counts['B']}, M {counts['M']}, V {counts['V']}, F 0, U 0, C 0" in text
    assert counts["M"] > 3 * 16 and counts["V"] > 2 * 16  # every curve became many chords
    assert f"from curves: {sum(data['curved_fold:edge_from_curve'])}" in text
    assert sum(data["curved_fold:edge_from_curve"]) == counts["M"] + counts["V"]
    assert f"wrote {out.resolve()}" in text
    assert set(data["edges_foldAngle"][i] for i, a in enumerate(data["edges_assignment"]) if a == "M") == {-180}


def test_given_parameters_and_warnings_are_printed(tmp_path: Path) -> None:
    svg = tmp_path / "w.svg"
    svg.write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100" width="100mm" height="100mm">'
        '<rect width="100" height="100" stroke="black"/><path d="M50 0 C 80 30 20 70 50 100" stroke="blue"/>'
        '<line stroke="#123456" x2="5"/></svg>'
    )
    out = tmp_path / "w.fold"
    res = run(str(svg), "--out", str(out), "--interval", "3", "--tolerance", "0.01", "--merge", "0.001")
    assert res.returncode == 0, res.stderr
    assert "interval: 3 mm (given)" in res.stdout and "merge tolerance: 0.001 mm (given)" in res.stdout
    assert "warning: w.svg: unknown stroke colours (elements skipped): #123456 (1 element: line 1)" in res.stdout
    assert out.exists()


@pytest.mark.parametrize(
    "args,message",
    [
        (["missing.svg", "--out", "x.fold"], "missing.svg: no such file"),
        ([str(EXAMPLES / "single_curve.svg"), "--out", "x.obj"], "the output must be a .fold file"),
        ([str(EXAMPLES / "single_curve.svg"), "--out", "x.fold", "--interval", "-2"], "--interval -2"),
        (
            [str(EXAMPLES / "single_curve.svg"), "--out", "x.fold", "--collection", "A"],
            "single_curve.svg: only a .blend file has collections to choose from ('A')",
        ),
        # a folder no one may write in (sysfs, even for root) is found before the work, naming the option
        ([str(EXAMPLES / "single_curve.svg"), "--out", "/sys/x.fold"], "--out /sys/x.fold: cannot write in /sys"),
    ],
)
def test_bad_input_exits_2_with_one_line(args: list[str], message: str, tmp_path: Path) -> None:
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    res = run(*args)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("curved_fold: error: ") and message in lines[0]


def test_malformed_svg_exits_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.svg"
    bad.write_text('<svg xmlns="http://www.w3.org/2000/svg">\n<line stroke="red"\n')
    res = run(str(bad), "--out", str(tmp_path / "o.fold"))
    assert res.returncode == 2 and "bad.svg: malformed XML at line 2, column 1: unclosed token" in res.stderr
    assert not (tmp_path / "o.fold").exists()


def test_fold_input_is_copied_through(tmp_path: Path) -> None:
    first, second = tmp_path / "a.fold", tmp_path / "b.fold"
    assert run(str(EXAMPLES / "concentric_arcs.svg"), "--out", str(first)).returncode == 0
    res = run(str(first), "--out", str(second))
    assert res.returncode == 0, res.stderr
    assert "parameters: none (a FOLD file of ours: its segments are read back as written)" in res.stdout
    assert second.read_bytes() == first.read_bytes()


def test_another_tools_fold_input_says_and_takes_its_parameters(tmp_path: Path) -> None:
    """Another tool's FOLD file is thinned and its border split at the interval and tolerance given (the summary
    said "parameters: none", and --interval was ignored)."""
    src, out = tmp_path / "other.fold", tmp_path / "o.fold"
    t = [i / 200 for i in range(201)]
    coords = [[0, 0], [100, 0], [100, 100], [0, 100]] + [[50 + 10 * math.sin(2 * math.pi * u), 100 * u] for u in t]
    edges = [[0, 1], [1, 2], [2, 3], [3, 0]] + [[4 + i, 5 + i] for i in range(200)]
    doc = {"vertices_coords": coords, "edges_vertices": edges, "edges_assignment": ["B"] * 4 + ["V"] * 200}
    src.write_text(json.dumps(doc | {"edges_foldAngle": [0] * 4 + [90] * 200, "frame_unit": "mm"}))
    res = run(str(src), "--out", str(out), "--interval", "3", "--tolerance", "0.02")
    assert res.returncode == 0, res.stderr
    assert "another tool's FOLD file: its dense polylines thinned, border and cuts split" in res.stdout
    assert "  interval: 3 mm (given)" in res.stdout and "  tolerance: 0.02 mm (given)" in res.stdout
    valleys = json.loads(out.read_text())["edges_assignment"].count("V")
    assert 20 < valleys < 200


def test_quiet_prints_nothing_and_still_writes(tmp_path: Path) -> None:
    out = tmp_path / "w.fold"
    res = run(str(FIXTURES / "wavy_pleats.svg"), "--out", str(out), "--quiet")
    assert res.returncode == 0, res.stderr
    assert res.stdout == "" and res.stderr == ""  # not a terminal: no progress line either
    assert json.loads(out.read_text())["edges_vertices"]


def test_out_equal_to_the_input_is_refused(tmp_path: Path) -> None:
    src = tmp_path / "p.fold"
    assert run(str(FIXTURES / "wavy_pleats.svg"), "--out", str(src), "-q").returncode == 0
    before = src.read_bytes()
    res = run(str(src), "--out", str(tmp_path / "." / "p.fold"))
    assert res.returncode == 2
    assert res.stderr.strip().endswith("is the input file " + str(src) + "; choose another output file")
    assert src.read_bytes() == before


def test_non_finite_parameters_are_refused() -> None:
    res = run(str(FIXTURES / "wavy_pleats.svg"), "--out", "/tmp/never-written.fold", "--interval", "inf")
    assert res.returncode == 2 and "--interval inf: must be a positive number of mm" in res.stderr
