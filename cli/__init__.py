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


def _load_blender(args: argparse.Namespace) -> None:
    """Load Blender's ``bpy`` up front when this run needs it — a .blend input (registers the Blender layer's .blend
    reader) or an output only the Blender layer writes (.glb, .obj, .stl, .blend, .svg) — with SIGINT and SIGTERM
    held until it is loaded (:func:`.core.io.atomic.signals_held`): raised while ``bpy`` registers its bundled
    add-ons, their error handling swallowed a Ctrl+C, and the run replaced the output file. Other runs (.svg/.fold
    in, .fold out) load it only if the ruling swaps need ``bmesh`` (a pattern with curve pieces,
    ``core.mesh.build``): it costs start-up time (~0.35 s CPU) and memory (~240 MB)."""
    source, out = str(getattr(args, "input", "")).lower(), str(getattr(args, "out", "") or "").lower()
    if not (source.endswith(".blend") or out.endswith((".blend", ".glb", ".gltf", ".obj", ".stl", ".svg"))):
        return
    from ..core import load_bpy
    from ..core.io.atomic import signals_held

    try:
        load_bpy()
        with signals_held():  # the Blender layer registers a reader; a Ctrl+C in there must not be swallowed either
            from ..scene import curves, export  # noqa: F401  (curves registers read_blend_file with core.io.reader)
    except ImportError:
        pass


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the process exit code (0 ok, 2 bad input or a failed write, 130 interrupted).

    Every expected failure is one line on stderr, never a traceback: bad input (:class:`PatternError`), a file
    that cannot be read or written (:class:`OSError`, naming the user's path), exhausted memory (a pattern too big
    for this machine) and too-deep recursion. SIGINT and SIGTERM remove any half-written temporary file first.
    """
    from ..core.io.atomic import install_signal_cleanup, restore_signal_handlers

    parser = build_parser()
    args = parser.parse_args(argv)
    previous = install_signal_cleanup()
    try:
        _load_blender(args)
        return int(args.func(args) or 0)
    except PatternError as exc:
        print(f"curved_fold: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader of the summary went away (`| head -1`); only the summary, printed after every file is written
        # (the exporters' own lines are guarded where they are passed on), can raise it, so the run succeeded
        from .outputs import stdout_to_devnull

        stdout_to_devnull()
        return 0
    except OSError as exc:
        print(f"curved_fold: error: {exc}", file=sys.stderr)
        return 2
    except MemoryError:
        print(
            "curved_fold: error: out of memory: the pattern is too large for this machine; pass a larger "
            "--interval and --tolerance, or split the pattern",
            file=sys.stderr,
        )
        return 2
    except RecursionError:
        print("curved_fold: error: the input is nested too deeply to process", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("curved_fold: interrupted (unfinished temporary files removed)", file=sys.stderr)
        return 130
    except SystemExit as exc:  # only SIGTERM raises it here (argparse's exits happen above)
        print("curved_fold: terminated (unfinished temporary files removed)", file=sys.stderr)
        raise exc
    finally:
        restore_signal_handlers(previous)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
