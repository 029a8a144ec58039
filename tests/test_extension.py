"""The add-on as Blender sees it: manifest, both builds, install from the zip, registration and clean unregistration."""

from __future__ import annotations

import importlib
import math
import os
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

from .conftest import REPO, extension_repository, load_build_tool

tool = load_build_tool()


def test_manifest_fields_and_validation():
    data = tool.manifest(REPO)
    assert data["id"] == "curved_fold"
    assert data["version"] == "0.1.0"
    assert data["type"] == "add-on"
    assert data["blender_version_min"] == "4.5.0"
    # no upper bound: no Blender version is known to break the add-on (docs/packaging.md, "Tested Blender versions")
    assert "blender_version_max" not in data
    assert data["license"] == ["SPDX:GPL-3.0-or-later"]
    assert len(data["tagline"]) <= 64 and data["tagline"][-1].isalnum()
    assert "wheels" not in data and "platforms" not in data, "the source manifest is the licence-clean one"
    assert "files" in data["permissions"]
    # Blender's own validator with the default valid-tags file (raises BuildError on any complaint).
    assert "Success" in tool.validate(REPO)


def test_validator_rejects_a_broken_manifest(tmp_path):
    """The validator really runs: a manifest with a bad tag and a two-number version is refused."""
    text = (REPO / "blender_manifest.toml").read_text()
    text = text.replace('version = "0.1.0"', 'version = "0.1"').replace('"Mesh",', '"Origami",')
    (tmp_path / "blender_manifest.toml").write_text(text)
    (tmp_path / "__init__.py").write_text("")
    with pytest.raises(tool.BuildError, match="version|Origami"):
        tool.validate(tmp_path)


def test_licence_clean_zip_contents(extension_zip: Path):
    with zipfile.ZipFile(extension_zip) as zf:
        names = set(zf.namelist())
        manifest = tomllib.loads(zf.read("blender_manifest.toml").decode())
    assert not [n for n in names if n.endswith(".whl")], "the licence-clean zip must not bundle any wheel"
    for required in (
        "__init__.py",
        "blender_manifest.toml",
        "core/pattern/model.py",
        "scene/curves.py",
        "cli/__init__.py",
    ):
        assert required in names
    dev_only = ("tests/", "docs/", "benchmarks/", "tools/", ".ci/", ".venv", "dist/", ".git/", "__pycache__")
    leaked = sorted(n for n in names if n.startswith(dev_only) or "__pycache__" in n)
    assert not leaked, f"dev-only files in the zip: {leaked[:5]}"
    assert not names & {"Makefile", "pyproject.toml", ".gitignore"}
    assert "wheels" not in manifest


@pytest.mark.slow
def test_bundled_zips_carry_cp311_and_cp313_triangle_wheels(tmp_path):
    try:
        tool.fetch_triangle_wheels()
    except tool.BuildError as exc:
        if "could not download" in str(exc):
            pytest.skip(f"PyPI not reachable to fetch the triangle wheels: {str(exc).splitlines()[0]}")
        raise
    zips = tool.build_bundled(tmp_path)
    by_platform = {z.name.rsplit("-", 1)[1].removesuffix(".zip"): z for z in zips}
    assert set(by_platform) == {"linux_x64", "macos_arm64", "windows_x64"}
    tags = {"linux_x64": "manylinux_2_17_x86_64", "macos_arm64": "macosx_11_0_arm64", "windows_x64": "win_amd64"}
    for platform, path in by_platform.items():
        with zipfile.ZipFile(path) as zf:
            wheels = sorted(Path(n).name for n in zf.namelist() if n.endswith(".whl"))
            manifest = tomllib.loads(zf.read("blender_manifest.toml").decode())
        assert len(wheels) == 2, wheels
        assert any("-cp311-cp311-" in w for w in wheels) and any("-cp313-cp313-" in w for w in wheels)
        assert all(w.startswith("triangle-20250106-") and tags[platform] in w for w in wheels)
        assert manifest["build"]["generated"]["platforms"] == [platform.replace("_", "-")]
    # The source manifest is untouched by the bundled build.
    assert "wheels" not in tool.manifest(REPO)


def test_extension_installed_from_zip_and_enabled(extension):
    import addon_utils  # importable once bpy is (the fixture imported it)

    assert extension.__name__ == "bl_ext.cf_pytest.curved_fold"
    assert addon_utils.check(extension.__name__) == (True, True)
    # Blender imported the copy installed from the zip into the test repository, not the working tree.
    installed = Path(extension.__file__).resolve().parent
    repo = extension_repository()
    assert installed == (Path(repo.directory) / "curved_fold").resolve()
    assert installed != REPO
    assert not (installed / "tests").exists() and (installed / "core" / "pattern" / "model.py").is_file()


def test_operators_and_properties_registered(extension, clean_scene):
    import bpy

    ops = dir(bpy.ops.curved_fold)
    assert {"set_crease_role", "select_by_role"} <= set(ops)
    assert "curved_fold" in bpy.types.Object.bl_rna.properties
    ob = bpy.data.objects.new("c", bpy.data.curves.new("c", "CURVE"))
    assert ob.curved_fold.role == "NONE"
    assert ob.curved_fold.fold_angle == pytest.approx(math.pi)
    assert "VIEW3D_PT_curved_fold_crease_role" in dir(bpy.types)


def test_cli_command_registered(extension, capsys, tmp_path):
    command_line = importlib.import_module(extension.__name__ + ".cli.blender")
    assert command_line.is_registered()
    # The callback Blender calls for `blender -c curved_fold ...` runs the package's command line.
    assert command_line.run_cli_command(["--help"]) == 0
    assert "usage: curved_fold" in capsys.readouterr().out
    assert command_line.run_cli_command(["no-such-subcommand"]) == 2


def test_disable_unregisters_cleanly_then_enable_again(extension):
    """Disabling leaves nothing of ours behind; enabling again restores everything (for the tests that follow)."""
    import bpy  # noqa: I001 - bpy first: it puts addon_utils on sys.path
    import addon_utils

    name = extension.__name__
    command_line = sys.modules[name + ".cli.blender"]
    addon_utils.disable(name, default_set=True)
    try:
        assert addon_utils.check(name)[1] is False
        assert not hasattr(bpy.types.Object, "curved_fold")
        assert dir(bpy.ops.curved_fold) == []
        assert not hasattr(bpy.types, "VIEW3D_PT_curved_fold_crease_role")
        assert not command_line.is_registered()
    finally:
        errors: list[str] = []
        addon_utils.enable(name, default_set=True, handle_error=lambda exc: errors.append(repr(exc)))
        assert not errors
    assert "set_crease_role" in dir(bpy.ops.curved_fold)
    assert hasattr(bpy.types.Object, "curved_fold")


INSTALL_BUNDLED = r"""
import sys
import bpy  # noqa: I001
import addon_utils
from bl_pkg import bl_extension_cli

bpy.ops.wm.read_factory_settings(use_empty=True)
rc = bl_extension_cli.cli_extension_handler(["install-file", "-r", "user_default", "-e", sys.argv[1]])
print("RC", rc)
print("ENABLED", addon_utils.check("bl_ext.user_default.curved_fold")[1])
site = bpy.utils.user_resource("EXTENSIONS", path=".local")
print("SITE", site)
# the extracted wheel must load in this Python (its ABI); put it before the venv's own copy of triangle
sys.path.insert(0, f"{site}/lib/python{sys.version_info[0]}.{sys.version_info[1]}/site-packages")
import triangle  # noqa: E402

print("TRIANGLE", triangle.__file__, len(triangle.triangulate({"vertices": [[0, 0], [1, 0], [0, 1]]})["triangles"]))
"""


@pytest.mark.slow
def test_bundled_linux_zip_installs_and_extracts_the_triangle_wheel_of_its_python(tmp_path):
    """Installing the self-hosted linux zip into bpy extracts only the wheel for Blender's own Python: cp311 in
    Blender 4.5/5.0, cp313 in 5.1/5.2 (the zip carries both), and the extension enables and imports it."""
    import subprocess

    try:
        zips = tool.build_bundled(tmp_path / "dist")
    except tool.BuildError as exc:
        if "could not download" in str(exc):
            pytest.skip(f"PyPI not reachable to fetch the triangle wheels: {str(exc).splitlines()[0]}")
        raise
    linux = next(z for z in zips if z.name.endswith("-linux_x64.zip"))
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    proc = subprocess.run(
        [sys.executable, "-c", INSTALL_BUNDLED, str(linux)], capture_output=True, text=True, env=env, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    keys = ("RC", "ENABLED", "SITE", "TRIANGLE")
    lines = dict(line.split(" ", 1) for line in proc.stdout.splitlines() if line.startswith(keys))
    assert lines["RC"] == "0" and lines["ENABLED"] == "True"
    major, minor = sys.version_info[:2]
    site_packages = list(Path(lines["SITE"]).glob("lib/python3.*/site-packages"))
    assert [p.parent.name for p in site_packages] == [f"python{major}.{minor}"]
    extracted = sorted(p.name for p in site_packages[0].iterdir())
    assert "triangle" in extracted
    assert any(name.startswith("triangle-20250106") and name.endswith(".dist-info") for name in extracted)
    native = list((site_packages[0] / "triangle").glob("*.so"))
    assert native and all(f"cpython-{major}{minor}-" in p.name for p in native), [p.name for p in native]
    module_file, n_triangles = lines["TRIANGLE"].rsplit(" ", 1)
    assert Path(module_file).is_relative_to(site_packages[0] / "triangle") and n_triangles == "1", lines["TRIANGLE"]
