"""Long fuzz run of the engine (the profile ``tests/test_fuzz.py`` runs briefly in CI).

Usage (from the repo root)::

    .venv/bin/python tools/fuzz_long.py --examples 2000 [--seed 1] [--readers 3000] [--json out/fuzz.json]

Draws ``--examples`` random crease patterns with the same hypothesis strategy as the CI test, folds each one and
counts what happened: folded (and how many were flagged "does not fold as assigned"), rejected with which catalogued
error, or a violation (uncatalogued exception, non-finite result, strain or time over the bound). Violations do not
stop the run: each is printed with the pattern that caused it. Exit status 1 if there was any violation.

``--readers N`` also fuzzes the two file readers with ``N`` documents each (the strategies of ``tests/test_fuzz.py``:
FOLD JSON with wrong types, nesting, huge numbers; SVG trees with bad attributes, stylesheets, deep nesting,
entities): each must be read or refused with a PatternError; any other exception is a violation. ``make fuzz``
runs both.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import traceback
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", type=int, default=2000, help="number of patterns to try (default 2000)")
    parser.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    parser.add_argument("--json", type=Path, default=None, help="also write the counts to this JSON file")
    parser.add_argument("--readers", type=int, default=0, help="also fuzz the FOLD and SVG readers (N documents each)")
    args = parser.parse_args(argv)

    from hypothesis import HealthCheck, given, seed, settings

    from curved_fold.tests.test_fuzz import STRAIN_BOUND_PCT, crease_patterns, fold_outcome

    counts: Counter[str] = Counter()
    violations: list[str] = []
    strain, seconds, iterations = [], [], []
    t_start = time.perf_counter()

    @seed(args.seed)
    @settings(
        max_examples=max(args.examples, 1),
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(curves=crease_patterns())
    def run(curves) -> None:
        try:
            out = fold_outcome(curves)
        except Exception as exc:  # a violation: record it with the pattern, keep going
            counts[f"VIOLATION: {type(exc).__name__}"] += 1
            where = "; ".join(
                f"{c.source} {c.assignment} {c.fold_angle} {[s.points.tolist() for s in c.segments]}" for c in curves
            )
            violations.append(f"{type(exc).__name__}: {exc}\n  pattern: {where}\n{traceback.format_exc(limit=3)}")
            return
        counts[f"{out.kind}: {out.detail}"] += 1
        if out.kind == "folded":
            strain.append(out.strain_max_pct)
            seconds.append(out.seconds)
            iterations.append(out.iterations)
        done = sum(counts.values())
        if done % 100 == 0:
            print(f"  {done} patterns, {time.perf_counter() - t_start:.0f} s", file=sys.stderr, flush=True)

    if args.examples > 0:
        run()
    if args.readers > 0:
        violations += fuzz_readers(args.readers, args.seed, counts)
    total = sum(counts.values())
    summary = {
        "patterns": total,
        "seed": args.seed,
        "wall_s": round(time.perf_counter() - t_start, 1),
        "counts": dict(sorted(counts.items())),
        "folded": sum(v for k, v in counts.items() if k.startswith("folded")),
        "rejected": sum(v for k, v in counts.items() if k.startswith("rejected")),
        "violations": len(violations),
        "strain_max_pct_worst": max(strain, default=0.0),
        "strain_bound_pct": STRAIN_BOUND_PCT,
        "seconds_worst": max(seconds, default=0.0),
        "iterations_worst": max(iterations, default=0),
    }
    print(json.dumps(summary, indent=2))
    for v in violations[:20]:
        print("\n" + v)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(summary, indent=2) + "\n")
    return 1 if violations else 0


def fuzz_readers(examples: int, seed_value: int, counts: Counter[str]) -> list[str]:
    """Fuzz the FOLD and SVG readers with ``examples`` documents each; counts "fold reader: read/refused" etc.
    and returns the violations (any exception other than PatternError, or a document over 10 s)."""
    from hypothesis import HealthCheck, given, seed, settings

    from curved_fold.tests.test_fuzz import fold_documents, read_fold_text, read_svg_text, svg_documents

    violations: list[str] = []

    def runner(name: str, strategy, reader):
        @seed(seed_value)
        @settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck))
        @given(text=strategy)
        def run(text: str) -> None:
            t0 = time.perf_counter()
            try:
                outcome = reader(text)
            except Exception as exc:  # a violation: record it with the document, keep going
                counts[f"VIOLATION ({name}): {type(exc).__name__}"] += 1
                violations.append(f"{name}: {type(exc).__name__}: {exc}\n  document: {text[:300]!r}")
                return
            dt = time.perf_counter() - t0
            if dt > 10.0:
                counts[f"VIOLATION ({name}): over 10 s"] += 1
                violations.append(f"{name}: {dt:.1f} s\n  document: {text[:300]!r}")
            counts[f"{name}: {outcome}"] += 1

        return run

    runner("fold reader", fold_documents(), read_fold_text)()
    runner("svg reader", svg_documents(), read_svg_text)()
    return violations


if __name__ == "__main__":
    sys.path.insert(0, str(REPO.parent))
    raise SystemExit(main())
