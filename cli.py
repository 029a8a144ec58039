"""The headless command line: ``python -m curved_fold <subcommand> ...``.

Each subcommand lives in a function ``_cmd_<name>`` and is registered in :func:`build_parser`. The same core
pipeline runs here, in Blender's ``blender -c curved_fold ...`` and behind the operators.
"""

from __future__ import annotations

import argparse
import sys

from .core.pattern import PatternError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="curved_fold",
        description="Fold curved-crease patterns (Bézier creases, ruling-aware triangulation, bar-and-hinge solver).",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    from . import commands

    commands.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the process exit code (0 ok, 2 bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
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
