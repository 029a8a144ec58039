"""Build (and validate) the Curved Fold extension zips with Blender's own extension builder.

Usage::

    python tools/build_extension.py --out dist/                    # licence-clean zip, no wheels
    python tools/build_extension.py --bundle-triangle --out dist/  # + self-hosted per-platform zips with `triangle`

No Blender binary is needed: ``blender --command extension build|validate`` is a thin wrapper around
``scripts/addons_core/bl_pkg/cli/blender_ext.py``, which ships inside the ``bpy`` wheel and uses only the standard
library. This script runs that file exactly as Blender does, with Blender's default valid-tags file, so the checks
(manifest fields, tags, permissions, wheel names) are the ones extensions.blender.org and ``install-file`` apply.

Two builds, for a licence reason (blender-notes §1.2 and §6.3):

* **licence-clean** (``curved_fold-<version>.zip``): the source manifest as it is, no wheels. Triangulation falls
  back to Blender's built-in ``mathutils.geometry.delaunay_2d_cdt``. Everything in it is GPL-compatible, so it is
  the zip for extensions.blender.org.
* **bundled** (``curved_fold-<version>-<platform>.zip``): adds the PyPI ``triangle`` wheels (cp311 for Blender
  4.5–5.0, cp313 for Blender 5.1+) for linux-x64, macos-arm64 and windows-x64, built with ``--split-platforms``.
  ``triangle`` wraps Shewchuk's Triangle, whose licence allows redistribution only without compensation and
  commercial use only by arrangement with its author: not GPL-compatible, so this zip is for self-hosting (e.g. a
  GitHub release), never for extensions.blender.org. Wheels must be bundled unmodified, so they are downloaded
  from PyPI with ``pip download --no-deps --only-binary=:all:`` into a cache folder outside the package.

The bundled build never touches the source manifest: it extracts the licence-clean zip (exactly the files that
belong to the extension) into a temporary folder, writes ``wheels`` and ``platforms`` into that copy's manifest and
builds from there.
"""

from __future__ import annotations

import argparse
import importlib.util
import shutil
import subprocess
import sys
import tempfile
import tomllib
import zipfile
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
"""The repository root, which is also the add-on package ``curved_fold``."""

TRIANGLE_VERSION = "20250106"
PYTHON_VERSIONS = ("3.11", "3.13")
"""Blender 4.5–5.0 run Python 3.11, Blender 5.1+ run 3.13: one zip per platform carries both wheels."""

PLATFORMS: dict[str, str] = {
    # Blender platform -> pip platform tag. manylinux_2_17 (= manylinux2014) is what triangle publishes; pip does
    # not fall back from the manual's manylinux_2_28 example, which finds nothing (blender-notes §1.2).
    "linux-x64": "manylinux_2_17_x86_64",
    "macos-arm64": "macosx_11_0_arm64",
    "windows-x64": "win_amd64",
}
"""Platforms for which PyPI has ``triangle`` wheels for both Python versions (no macOS x64, no arm64 Linux)."""

DEFAULT_WHEEL_CACHE = REPO / ".venv" / "wheels-cache"


class BuildError(RuntimeError):
    """The builder or validator rejected the package, or a wheel could not be fetched (message says which)."""


@dataclass(frozen=True)
class BlenderTools:
    """Blender's extension CLI (``blender_ext.py``) and the valid-tags file it is given by default."""

    blender_ext: Path
    tags: Path


def find_blender_tools() -> BlenderTools:
    """Locate ``blender_ext.py`` and ``tags.py`` inside the installed ``bpy`` wheel, without importing ``bpy``."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        raise BuildError("the 'bpy' module is not installed in this Python; run `make setup` first")
    root = Path(next(iter(spec.submodule_search_locations)))
    for version_dir in sorted(root.iterdir(), reverse=True):
        ext = version_dir / "scripts" / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
        tags = version_dir / "scripts" / "modules" / "_bpy_internal" / "extensions" / "tags.py"
        if ext.is_file() and tags.is_file():
            return BlenderTools(ext, tags)
    raise BuildError(f"no scripts/addons_core/bl_pkg/cli/blender_ext.py found under {root}")


def run_blender_ext(args: list[str], tools: BlenderTools | None = None) -> str:
    """Run ``blender_ext.py <args>`` as ``blender --command extension`` would; return its output, raise on failure."""
    tools = tools or find_blender_tools()
    command = args[0]
    cmd = [sys.executable, str(tools.blender_ext), command]
    if command in ("build", "validate"):
        cmd += ["--valid-tags", str(tools.tags)]
    cmd += args[1:]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    output = (proc.stdout + proc.stderr).strip()
    if proc.returncode != 0 or "FATAL_ERROR" in output or "Error:" in output:
        raise BuildError(f"`blender_ext.py {' '.join(args)}` failed (exit {proc.returncode}):\n{output}")
    return output


def manifest(source: Path = REPO) -> dict:
    """The parsed ``blender_manifest.toml`` of ``source``."""
    with open(source / "blender_manifest.toml", "rb") as fh:
        return tomllib.load(fh)


def validate(path: Path = REPO) -> str:
    """Validate a package folder or a built zip with Blender's validator (strict tags); return its message."""
    return run_blender_ext(["validate", str(path)])


def build_clean(out: Path, source: Path = REPO) -> Path:
    """Validate and build the licence-clean zip (no wheels) into ``out``; return the zip's path."""
    out.mkdir(parents=True, exist_ok=True)
    data = manifest(source)
    if data.get("wheels"):
        raise BuildError(f"{source / 'blender_manifest.toml'}: the source manifest must not list wheels")
    validate(source)
    zip_path = out / f"{data['id']}-{data['version']}.zip"
    if zip_path.exists():
        zip_path.unlink()
    run_blender_ext(["build", "--source-dir", str(source), "--output-dir", str(out)])
    if not zip_path.is_file():
        raise BuildError(f"the builder reported success but {zip_path} does not exist")
    validate(zip_path)
    return zip_path


def wheel_name(python_version: str, platform: str) -> str:
    """PEP 427 file name of the ``triangle`` wheel PyPI publishes for a Python version and Blender platform."""
    cp = "cp" + python_version.replace(".", "")
    tag = {
        "linux-x64": "manylinux_2_17_x86_64.manylinux2014_x86_64",
        "macos-arm64": "macosx_11_0_arm64",
        "windows-x64": "win_amd64",
    }[platform]
    return f"triangle-{TRIANGLE_VERSION}-{cp}-{cp}-{tag}.whl"


def fetch_triangle_wheels(cache: Path = DEFAULT_WHEEL_CACHE) -> list[Path]:
    """Download (once) the unmodified ``triangle`` wheels for every Python version × platform into ``cache``."""
    cache.mkdir(parents=True, exist_ok=True)
    wheels = []
    for platform, pip_tag in PLATFORMS.items():
        for py in PYTHON_VERSIONS:
            path = cache / wheel_name(py, platform)
            if not path.is_file():
                cmd = [sys.executable, "-m", "pip", "download", "--quiet", "--disable-pip-version-check"]
                cmd += ["--no-deps", "--only-binary=:all:", "--python-version", py, "--platform", pip_tag]
                cmd += ["--dest", str(cache), f"triangle=={TRIANGLE_VERSION}"]
                proc = subprocess.run(cmd, capture_output=True, text=True)
                if proc.returncode != 0 or not path.is_file():
                    raise BuildError(
                        f"could not download {path.name} (Python {py}, {platform}) from PyPI:\n"
                        f"{(proc.stdout + proc.stderr).strip()}"
                    )
            wheels.append(path)
    return wheels


def _toml_list(values: list[str]) -> str:
    return "[\n" + "".join(f'  "{v}",\n' for v in values) + "]"


def build_bundled(out: Path, source: Path = REPO, cache: Path = DEFAULT_WHEEL_CACHE) -> list[Path]:
    """Build the self-hosted per-platform zips that bundle the ``triangle`` wheels; return their paths."""
    out.mkdir(parents=True, exist_ok=True)
    wheels = fetch_triangle_wheels(cache)
    data = manifest(source)
    with tempfile.TemporaryDirectory(prefix="curved_fold_bundle_") as tmp:
        tmp = Path(tmp)
        clean = build_clean(tmp / "clean", source)
        package = tmp / data["id"]
        with zipfile.ZipFile(clean) as zf:
            zf.extractall(package)
        (package / "wheels").mkdir()
        for wheel in wheels:
            shutil.copy2(wheel, package / "wheels" / wheel.name)
        # Top-level keys must come before the first [table]; insert them there in the copy's manifest.
        text = (package / "blender_manifest.toml").read_text(encoding="utf-8")
        lines = text.splitlines(keepends=True)
        first_table = next(i for i, line in enumerate(lines) if line.lstrip().startswith("["))
        extra = (
            "\n# Added by tools/build_extension.py --bundle-triangle (self-hosted build, see its docstring).\n"
            f"platforms = {_toml_list(list(PLATFORMS))}\n"
            f"wheels = {_toml_list([f'./wheels/{w.name}' for w in wheels])}\n\n"
        )
        (package / "blender_manifest.toml").write_text(
            "".join(lines[:first_table]) + extra + "".join(lines[first_table:])
        )
        validate(package)
        before = set(out.glob(f"{data['id']}-{data['version']}-*.zip"))
        for stale in before:
            stale.unlink()
        run_blender_ext(["build", "--source-dir", str(package), "--output-dir", str(out), "--split-platforms"])
    zips = sorted(out.glob(f"{data['id']}-{data['version']}-*.zip"))
    if len(zips) != len(PLATFORMS):
        raise BuildError(f"expected {len(PLATFORMS)} platform zips in {out}, found {[z.name for z in zips]}")
    for z in zips:
        validate(z)
    return zips


def _describe(path: Path) -> str:
    with zipfile.ZipFile(path) as zf:
        names = zf.namelist()
    wheels = sorted(Path(n).name for n in names if n.endswith(".whl"))
    size = path.stat().st_size / 1e6
    text = f"  {path} ({size:.2f} MB, {len(names)} files"
    text += f", wheels: {', '.join(wheels)})" if wheels else ", no wheels)"
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=REPO / "dist", help="output folder (default: dist/)")
    parser.add_argument(
        "--bundle-triangle",
        action="store_true",
        help="also build self-hosted per-platform zips bundling the triangle wheels (not for extensions.blender.org)",
    )
    parser.add_argument("--wheel-cache", type=Path, default=DEFAULT_WHEEL_CACHE, help="where wheels are downloaded")
    args = parser.parse_args(argv)
    try:
        clean = build_clean(args.out)
        print("built licence-clean extension (for extensions.blender.org):")
        print(_describe(clean))
        if args.bundle_triangle:
            zips = build_bundled(args.out, cache=args.wheel_cache)
            print("built self-hosted extensions bundling triangle (LGPL wrapper of non-GPL Triangle; do not upload):")
            for z in zips:
                print(_describe(z))
    except BuildError as exc:
        print(f"build_extension: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
