"""The Newton solver's sparse factorisation, old against new: the level-set band (``core/solve/linalg.py``,
``BlockTridiagonal``) and nested dissection with multifrontal Cholesky (``core/solve/dissection.py``,
``NestedDissection``).

For each case a Hessian is assembled by a ``HessianAssembler`` of each kind: the exact one of a fixture folded to
100 % with ``Solver(mesh).solve(1.0)``, shifted by 1e-3 of the force scale plus the rigid rotations' lift (as an
exact Newton step near convergence), or the Gauss–Newton one of a square ``grid_mesh(k, k)`` with its nodes
jittered, shifted by 1e-3 (a Gauss–Newton step). Each is factored with ``inertia=True`` and solved once, old and
new interleaved, ``--repeats`` times each (CPU time,
``time.process_time``, one BLAS thread): medians, the flops of one factorisation with Cholesky pivots, the number of
blocks or supernodes, the setup time (ordering and scatter indices) and the largest difference of the two solves.
``--fold`` also times whole folds of CircularPleat-antiFacet at 100 % with either (iterations, CPU, energy, how far
apart the two final states are), ``--fold-all`` those of every fixture at 60 and 100 %, old and new interleaved.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python -m curved_fold.benchmarks.factorisation [--repeats N] [--fold]``.
Not part of ``make bench`` (a minute or two); it prints markdown tables.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

if __package__ in (None, ""):  # run as a script: make the add-on importable as ``curved_fold``
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from curved_fold.benchmarks.common import FIXTURES, REPO, load_average, markdown_table  # noqa: E402
from curved_fold.core.io.reader import read_pattern  # noqa: E402
from curved_fold.core.mesh.build import build_mesh  # noqa: E402
from curved_fold.core.solve import forces as F  # noqa: E402, N812
from curved_fold.core.solve.dissection import NestedDissection  # noqa: E402
from curved_fold.core.solve.linalg import BlockTridiagonal, single_threaded_blas  # noqa: E402
from curved_fold.core.solve.newton import HessianAssembler, rigid_shift  # noqa: E402
from curved_fold.core.solve.solver import Solver, rigid_rms  # noqa: E402

FIXTURE_CASES = ("CircularPleat-antiFacet.svg", "Carved_Cylinder.svg", "Treble_Clef.svg", "Rotating_Star.svg")
GRID_SIZES = (10, 20, 30, 40, 50, 60)
KINDS = (("old", BlockTridiagonal), ("new", NestedDissection))


def flops(matrix: Any) -> float:
    """Flops of one factorisation with Cholesky pivots (potrf s³/3, trsm, syrk) of either kind."""
    if isinstance(matrix, NestedDissection):
        return matrix.flops()
    s = matrix.sizes.astype(np.float64)
    nxt = np.append(s[1:], 0.0)
    return float(np.sum(s**3 / 3 + s * s * nxt + s * nxt * nxt))


def blocks(matrix: Any) -> int:
    return len(matrix.supernodes) if isinstance(matrix, NestedDissection) else len(matrix.sizes)


def grid_state(k: int):
    """A ``k × k`` grid sheet (``tests/test_forces.grid_mesh``, 80 mm) with nodes jittered by 1 % of its size."""
    sys.path.insert(0, str(REPO.parent))  # tests/ is a package next to the add-on's modules
    from tests.test_forces import grid_mesh

    solver = Solver(grid_mesh(k, k, 80.0))
    x = solver.model.rest + np.random.default_rng(k).normal(0, 0.01, solver.model.rest.shape)
    return solver, x, F.fold_angles(solver.model, x)


def folded_state(name: str):
    """A fixture folded to 100 % (the state a fold's last factorisations see)."""
    solver = Solver(build_mesh(read_pattern(FIXTURES / name), mesh_type="ruling"))
    result = solver.solve(1.0)
    return solver, solver.model.from_mm(result.positions), result.theta


def compare(
    label: str, solver: Solver, x: np.ndarray, theta: np.ndarray, repeats: int, exact: bool = True
) -> dict[str, Any]:
    """Old and new factorisation and solve of the exact (or Gauss–Newton) Hessian at ``x``, interleaved (see the
    module doc)."""
    model = solver.model
    ev = F.evaluate(model, x, theta, 1.0, jacobians=True)
    shift = 1e-3 * solver.force_scale + (rigid_shift(x, ev.forces) if exact else 0.0)
    rhs = np.random.default_rng(0).normal(size=3 * model.n_nodes)
    row: dict[str, Any] = {"case": label, "nodes": model.n_nodes, "faces": len(model.triangles)}
    work = {}
    for kind, cls in KINDS:
        t = time.process_time()
        assembler = HessianAssembler(model, cls(model.n_nodes, HessianAssembler.coupling_pairs(model)))
        row[f"{kind} setup ms"] = (time.process_time() - t) * 1e3
        work[kind] = (assembler.matrix, assembler.assemble_exact(x, ev) if exact else assembler.assemble(ev))
        row[f"{kind} MFLOP"] = flops(assembler.matrix) / 1e6
        row[f"{kind} blocks"] = blocks(assembler.matrix)
    times: dict[str, list[list[float]]] = {kind: [[], []] for kind, _ in KINDS}
    solutions = {}
    with single_threaded_blas():
        for _ in range(repeats):
            for kind, (matrix, storage) in work.items():
                t = time.process_time()
                factor = matrix.factor(storage, shift, inertia=True)
                t1 = time.process_time()
                solutions[kind] = (factor.apply(rhs), factor.negative_pivots)
                times[kind][0].append(t1 - t)
                times[kind][1].append(time.process_time() - t1)
    for kind, (tf, ta) in times.items():
        row[f"{kind} factor ms"] = float(np.median(tf)) * 1e3
        row[f"{kind} apply ms"] = float(np.median(ta)) * 1e3
    row["speedup"] = row["old factor ms"] / row["new factor ms"]
    old, new = solutions["old"][0], solutions["new"][0]
    row["difference"] = float(np.max(np.abs(old - new)) / np.max(np.abs(old)))
    row["inertia"] = f"{solutions['old'][1]}/{solutions['new'][1]}"
    return row


def fold(repeats: int, names: tuple[str, ...] = ("CircularPleat-antiFacet.svg",), percents=(1.0,)) -> list[dict]:
    """Whole folds (``Solver(mesh).solve(percent)``) with either factorisation, old and new interleaved."""
    rows = []
    for name in names:
        mesh = build_mesh(read_pattern(FIXTURES / name), mesh_type="ruling")
        for percent in percents:
            cpu: dict[str, list[float]] = {kind: [] for kind, _ in KINDS}
            results = {}
            for _ in range(repeats):
                for kind, cls in KINDS:
                    solver = Solver(mesh)
                    pairs = HessianAssembler.coupling_pairs(solver.model)
                    solver._assembler = HessianAssembler(solver.model, cls(solver.model.n_nodes, pairs))  # else lazily
                    t = time.process_time()
                    results[kind] = solver.solve(percent)
                    cpu[kind].append(time.process_time() - t)
            old, new = results["old"], results["new"]
            rows.append(
                {
                    "case": f"{name} {percent:.0%}",
                    "iterations": f"{old.iterations} → {new.iterations}",
                    "cpu old": float(np.median(cpu["old"])),
                    "cpu new": float(np.median(cpu["new"])),
                    "per iteration": f"{np.median(cpu['old']) / old.iterations * 1e3:.1f} → "
                    f"{np.median(cpu['new']) / new.iterations * 1e3:.1f}",
                    "energy": f"{new.energy:.10g}",
                    "energy difference": abs(new.energy - old.energy) / max(abs(old.energy), 1e-300),
                    "positions": rigid_rms(old.positions, new.positions),
                }
            )
            print(f"{rows[-1]['case']}: {rows[-1]}", flush=True)
    return rows


FOLD_COLUMNS = [
    ("fold", "case", "s"),
    ("iterations old → new", "iterations", "s"),
    ("CPU s old", "cpu old", ".2f"),
    ("CPU s new", "cpu new", ".2f"),
    ("ms per iteration old → new", "per iteration", "s"),
    ("energy", "energy", "s"),
    ("energy rel. difference", "energy difference", ".0e"),
    ("positions apart (mm, rigid RMS)", "positions", ".0e"),
]


COLUMNS = [
    ("case", "case", "s"),
    ("nodes", "nodes", "d"),
    ("old factor ms", "old factor ms", ".1f"),
    ("new factor ms", "new factor ms", ".1f"),
    ("speedup", "speedup", ".2f"),
    ("old apply ms", "old apply ms", ".2f"),
    ("new apply ms", "new apply ms", ".2f"),
    ("old MFLOP", "old MFLOP", ".0f"),
    ("new MFLOP", "new MFLOP", ".0f"),
    ("old blocks", "old blocks", "d"),
    ("new supernodes", "new blocks", "d"),
    ("old setup ms", "old setup ms", ".0f"),
    ("new setup ms", "new setup ms", ".0f"),
    ("solve difference", "difference", ".0e"),
    ("negative pivots old/new", "inertia", "s"),
]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--fold", action="store_true", help="also time whole CircularPleat-antiFacet folds")
    parser.add_argument("--fold-all", action="store_true", help="whole folds of every fixture at 60 and 100 %%")
    parser.add_argument("--fold-repeats", type=int, default=5)
    parser.add_argument("--grids", type=int, nargs="*", default=list(GRID_SIZES))
    args = parser.parse_args(argv)
    print(f"load average {load_average()[0]:.2f}; CPU time, medians of {args.repeats}\n")
    rows = []
    for name in FIXTURE_CASES:
        rows.append(compare(name, *folded_state(name), args.repeats))
        print(markdown_table(rows[-1:], COLUMNS).splitlines()[-1], flush=True)
    for k in args.grids:
        rows.append(compare(f"grid {k}×{k}", *grid_state(k), args.repeats, exact=False))
        print(markdown_table(rows[-1:], COLUMNS).splitlines()[-1], flush=True)
    print()
    print(markdown_table(rows, COLUMNS))
    if args.fold or args.fold_all:
        names = (
            tuple(sorted(p.name for p in FIXTURES.glob("*.svg"))) if args.fold_all else ("CircularPleat-antiFacet.svg",)
        )
        percents = (0.6, 1.0) if args.fold_all else (1.0,)
        print()
        print(markdown_table(fold(args.fold_repeats, names, percents), FOLD_COLUMNS))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
