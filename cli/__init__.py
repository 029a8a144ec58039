"""The command line, one home for its three doors: ``python -m curved_fold <subcommand> ...``,
``blender -c curved_fold <subcommand> ...`` (:mod:`.blender`) and scripts calling :func:`main`.

Each subcommand is a module here with ``register(sub)`` (``discretize``, ``fold``), added by :func:`build_parser`.
The same core pipeline runs here and behind the operators.
"""

from __future__ import annotations

import argparse
import sys

from ..core.pattern.model import PatternError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="curved_fold",
        description="Fold curved-crease patterns (Bézier creases, ruling-aware triangulation, bar-and-hinge solver).",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    from . import discretize, fold

    discretize.register(sub)
    fold.register(sub)
    return parser


def _enable_blend_files() -> None:
    """Register the .blend reader of the Blender layer when ``bpy`` can be imported (it cannot in plain Python)."""
    try:
        from ..scene import curves  # noqa: F401  (registers scene.curves.read_blend_file with core.io.reader)
    except ImportError:
        pass


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the process exit code (0 ok, 2 bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    _enable_blend_files()
    try:
        return int(args.func(args) or 0)
    except PatternError as exc:
        print(f"curved_fold: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"curved_fold: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
