"""Shared helpers for ``make bench`` (benchmarks/run.py): machine header, timing, peak memory, time budget, Pareto
front, exponent fits and markdown tables.

Nothing here asserts anything about time: a benchmark measures and reports; the smoke test only checks it runs.
"""

from __future__ import annotations

import importlib.metadata
import math
import os
import platform
import time
import tracemalloc
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FIXTURES = REPO / "tests" / "fixtures" / "origami-simulator"
EXAMPLES = REPO / "examples"
DOCS = REPO / "docs"
IMG = DOCS / "img"


def load_average() -> tuple[float, float, float]:
    """``os.getloadavg()`` (1, 5, 15 minutes), or nans where the OS has none."""
    try:
        return os.getloadavg()
    except OSError:  # pragma: no cover - not on Linux
        return (float("nan"),) * 3


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "absent"


def machine() -> dict[str, Any]:
    """CPU model, core count, OS, Python and library versions, BLAS, and the load average now."""
    cpu = platform.processor() or "unknown"
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next((ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")), cpu)
    except OSError:  # pragma: no cover - not on Linux
        pass
    blas = "unknown"
    try:
        cfg = np.show_config(mode="dicts")  # numpy ≥ 1.26
        info = cfg.get("Build Dependencies", {}).get("blas", {})
        blas = f"{info.get('name', '?')} {info.get('version', '')}".strip()
    except Exception:  # noqa: BLE001 - older numpy: the BLAS name is only cosmetic
        pass
    try:
        import bpy  # noqa: F401 - only to read its version

        bpy_version = ".".join(str(v) for v in bpy.app.version)
    except Exception:  # noqa: BLE001 - bpy missing: the core benchmarks still run
        bpy_version = "absent"
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "os": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
        "numpy": np.__version__,
        "blas": blas,
        "triangle": _version("triangle"),
        "matplotlib": _version("matplotlib"),
        "bpy": bpy_version,
        "load": load_average(),
    }


def machine_lines(info: dict[str, Any]) -> list[str]:
    """Human-readable header lines for the report."""
    la = info["load"]
    return [
        f"- CPU: {info['cpu']}, {info['cores']} cores; {info['os']}",
        f"- Python {info['python']}, numpy {info['numpy']} ({info['blas']}), triangle {info['triangle']}, "
        f"bpy {info['bpy']}, matplotlib {info['matplotlib']}",
        f"- load average at the start (1/5/15 min): {la[0]:.2f} / {la[1]:.2f} / {la[2]:.2f}",
    ]


def timed(fn: Callable[[], Any]) -> tuple[Any, float]:
    """Run ``fn()`` and return ``(result, wall ms)`` (``time.perf_counter``)."""
    t0 = time.perf_counter()
    out = fn()
    return out, (time.perf_counter() - t0) * 1000.0


def peak_memory(fn: Callable[[], Any]) -> tuple[Any, float]:
    """Run ``fn()`` under ``tracemalloc`` and return ``(result, peak MiB allocated during the call)``.

    numpy reports its array buffers to tracemalloc, so this is the peak of Python objects plus numpy arrays created
    by the call (not the process RSS, which includes the interpreter, bpy and earlier runs). Tracing slows the call
    down: never time a call that is traced.
    """
    was = tracemalloc.is_tracing()
    if not was:
        tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    try:
        out = fn()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        if not was:
            tracemalloc.stop()
    return out, max(peak - base, 0) / 2**20


@dataclass
class Budget:
    """Wall-clock budget of one benchmark run, split into named sections (seconds).

    Each section may spend its share; :meth:`left` tells a section how much it still has so it can cap its runs
    (faithful steps, scaling sizes) and skip what does not fit, saying so in the report.
    """

    shares: dict[str, float]
    started: float = field(default_factory=time.perf_counter)
    section_started: dict[str, float] = field(default_factory=dict)
    spent: dict[str, float] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)

    def start(self, name: str) -> None:
        self.section_started[name] = time.perf_counter()

    def stop(self, name: str) -> None:
        self.spent[name] = time.perf_counter() - self.section_started.pop(name)

    def left(self, name: str) -> float:
        """Seconds the running section ``name`` may still spend."""
        used = time.perf_counter() - self.section_started.get(name, time.perf_counter())
        return self.shares.get(name, 0.0) - used

    def skip(self, what: str) -> None:
        self.skipped.append(what)

    @property
    def elapsed(self) -> float:
        return time.perf_counter() - self.started


def pareto_mask(cost: Sequence[float], error: Sequence[float]) -> np.ndarray:
    """Mask of the points no other point beats on both cost and error (ties on both keep the first)."""
    c = np.asarray(cost, dtype=float)
    e = np.asarray(error, dtype=float)
    keep = np.zeros(len(c), dtype=bool)
    best = math.inf
    for k in np.lexsort((e, c)):  # by cost, then error: a point is on the front if it beats every cheaper one
        if np.isfinite(e[k]) and np.isfinite(c[k]) and e[k] < best:
            keep[k] = True
            best = e[k]
    return keep


def fit_exponent(x: Sequence[float], y: Sequence[float]) -> tuple[float, float]:
    """Least-squares slope of log y against log x and its standard error: ``y ≈ a·x^slope``.

    Points with non-positive or non-finite values are ignored; ``(nan, nan)`` with fewer than 2 points.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    if ok.sum() < 2:
        return float("nan"), float("nan")
    lx, ly = np.log(x[ok]), np.log(y[ok])
    a = np.vstack([lx, np.ones_like(lx)]).T
    coef, *_ = np.linalg.lstsq(a, ly, rcond=None)
    if ok.sum() < 3:
        return float(coef[0]), float("nan")
    resid = ly - a @ coef
    s2 = float(resid @ resid) / (ok.sum() - 2)
    cov = s2 * np.linalg.inv(a.T @ a)
    return float(coef[0]), float(math.sqrt(cov[0, 0]))


def fmt(value: Any, spec: str = "") -> str:
    """One table cell: ``–`` for missing/nan, yes/no for booleans, else ``format(value, spec)``."""
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float) and not math.isfinite(value):
        return "–"
    try:
        return format(value, spec)
    except (TypeError, ValueError):
        return str(value)


def markdown_table(rows: Iterable[dict[str, Any]], columns: Sequence[tuple[str, str, str]]) -> str:
    """Markdown table; ``columns`` are ``(header, key, format spec)``; a row with ``error`` spans the rest."""
    lines = ["| " + " | ".join(c[0] for c in columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        if "error" in r:
            lines.append(f"| {fmt(r.get(columns[0][1]))} | error: {r['error']} |" + " |" * (len(columns) - 2))
            continue
        lines.append("| " + " | ".join(fmt(r.get(key), spec) for _, key, spec in columns) + " |")
    return "\n".join(lines)


def spread(values: Sequence[float]) -> dict[str, float]:
    """min, median and max of the finite values (nans when there are none)."""
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], dtype=float)
    if len(v) == 0:
        return {"min": float("nan"), "median": float("nan"), "max": float("nan"), "n": 0}
    return {"min": float(v.min()), "median": float(np.median(v)), "max": float(v.max()), "n": int(len(v))}


def replace_section(path: Path, begin: str, end: str, body: str) -> None:
    """Write ``body`` (which starts with ``begin`` and ends with ``end``) over the section between those markers in
    ``path``, or append it when the markers are absent; atomically."""
    from curved_fold.core.io.atomic import atomic_write_text

    text = path.read_text() if path.exists() else ""
    if begin in text and end in text:
        text = text[: text.index(begin)] + body + text[text.index(end) + len(end) :]
    else:
        text = text.rstrip() + "\n\n" + body + "\n"
    atomic_write_text(path, text)
