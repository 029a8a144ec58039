"""Smoke run of ``make bench`` (benchmarks/run.py --quick) so the benchmark never rots, plus its small helpers.

A benchmark is not a test: nothing here checks a time. It checks that every section runs on one small case and
writes a complete report (markdown, JSON, PNGs) into a temporary folder, leaving docs/ alone.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from curved_fold.benchmarks.common import fit_exponent, markdown_table, pareto_mask, spread


def test_pareto_mask_keeps_only_points_nothing_beats() -> None:
    cost = [1.0, 2.0, 3.0, 2.5, 0.5, 4.0]
    error = [5.0, 1.0, 0.5, 2.0, 9.0, 0.5]
    mask = pareto_mask(cost, error)
    # (2.5, 2.0) is beaten by (2.0, 1.0); (4.0, 0.5) by (3.0, 0.5)
    assert mask.tolist() == [True, True, True, False, True, False]


def test_fit_exponent_recovers_a_power_law() -> None:
    x = np.array([150, 600, 2400, 9600, 20000], dtype=float)
    slope, err = fit_exponent(x, 3.0 * x**1.3 * np.array([1.02, 0.98, 1.01, 0.99, 1.0]))
    assert slope == pytest.approx(1.3, abs=0.02)
    assert 0 < err < 0.05
    assert math.isnan(fit_exponent([1.0], [2.0])[0])


def test_table_and_spread_helpers() -> None:
    text = markdown_table([{"a": "x", "b": 1.23456}, {"a": "y", "error": "boom"}], [("A", "a", "s"), ("B", "b", ".2f")])
    assert "| x | 1.23 |" in text and "error: boom" in text
    s = spread([3.0, float("nan"), 1.0, 2.0])
    assert (s["min"], s["median"], s["max"], s["n"]) == (1.0, 2.0, 3.0, 3)


@pytest.mark.slow
def test_quick_bench_run_writes_a_complete_report(tmp_path) -> None:
    from curved_fold.benchmarks import run

    doc = tmp_path / "benchmarks.md"
    assert run.main(["--quick", "--doc", str(doc), "--out", str(tmp_path), "--img", str(tmp_path)]) == 0
    text = doc.read_text()
    for heading in ("## 1. Table 1", "## 2. Speed against error", "## 3. Scaling", "## 4. Fast ÷ faithful"):
        assert heading in text
    assert "QUICK smoke run" in text and "load average at the end" in text
    assert "| 8(l) | 1822 | 611 | 3111 |" in text  # the paper's table beside ours
    report = json.loads((tmp_path / "benchmarks.json").read_text())
    rows = [r for r in report["table1"] if "error" not in r]
    assert rows, report["table1"]
    for r in rows:
        assert r["faces"] > 0 and r["fast_converged"] and r["faithful_steps"] > 0
        assert math.isfinite(r["strain_pct"]) and math.isfinite(r["warp_with"])
    sweep = [r for r in report["speed_error"]["all_rows"] if "rms" in r]
    assert {r["solver"] for r in sweep} == {"fast", "isometric", "faithful"}
    assert all(r["rms"] >= 0 for r in sweep)
    assert len(report["scaling"]["rows"]) == 2 and report["scaling"]["rows"][1]["faces"] > 300
    for name in ("bench_speed_error.png", "bench_warp_strain.png", "bench_scaling.png"):
        png = tmp_path / name
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


def test_mesh_table_rewrites_only_its_section_of_the_document(tmp_path) -> None:
    """``benchmarks/mesh_table.py`` used to write the whole of docs/meshes.md from a template that had fallen behind
    the hand-written notes (running it would have deleted them); it now replaces only its marked section."""
    from curved_fold.benchmarks.common import replace_section
    from curved_fold.benchmarks.mesh_table import MESH_BEGIN, MESH_END, render_markdown

    row = {"name": "x.svg", "vertices": 4, "curve_segments": 0, "earcut": {"faces": 2, "ms": 1.0}}
    row |= {"cdt": {"faces": 2, "ms": 1.0}, "ruling": {"faces": 2, "ms": 1.5, "swaps": 1}}
    body = render_markdown([row], 3)
    assert body.startswith(MESH_BEGIN) and body.endswith(MESH_END) and "| x.svg | 4 | 0 | 2 |" in body
    doc = tmp_path / "meshes.md"
    doc.write_text(f"# Title\n\n{MESH_BEGIN}\nold table\n{MESH_END}\n\n## Notes by hand\n")
    replace_section(doc, MESH_BEGIN, MESH_END, body)
    text = doc.read_text()
    assert text.startswith("# Title\n\n" + MESH_BEGIN) and text.endswith(MESH_END + "\n\n## Notes by hand\n")
    assert "old table" not in text and "| x.svg |" in text


def test_make_bench_keeps_the_hand_written_sections_of_its_document(tmp_path) -> None:
    """``make bench`` regenerates docs/benchmarks.md; it used to drop the jobs section written by hand below it."""
    from curved_fold.benchmarks.run import HAND_WRITTEN, write_doc

    doc = tmp_path / "benchmarks.md"
    write_doc(doc, "# Benchmarks\n\nfirst run\n")
    assert doc.read_text().startswith("# Benchmarks\n\nfirst run\n\n" + HAND_WRITTEN)
    doc.write_text(doc.read_text().rstrip() + "\n\n## Jobs\n\nby hand\n")
    write_doc(doc, "# Benchmarks\n\nsecond run\n")
    text = doc.read_text()
    assert "second run" in text and "first run" not in text and text.endswith(HAND_WRITTEN + "\n\n## Jobs\n\nby hand\n")
