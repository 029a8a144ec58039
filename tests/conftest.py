"""Shared pytest harness: test the add-on AS BLENDER LOADS IT (built zip → installed extension → enabled).

Pure engine tests (``core``, CLI) need nothing from here and never import ``bpy``: the fixtures below are not
autouse, so they pay nothing.

Blender-level tests ask for two fixtures::

    import importlib

    def test_fold_operator(extension, clean_scene):
        # `extension` is the enabled module, e.g. bl_ext.cf_pytest.curved_fold
        curves = importlib.import_module(extension.__name__ + ".scene.curves")   # the INSTALLED copy
        ...
        assert bpy.ops.curved_fold.set_crease_role(role="VALLEY") == {"FINISHED"}

* ``extension`` (session): once per session it resets Blender with ``read_factory_settings(use_empty=True)``,
  builds the licence-clean zip with Blender's own builder (``tools/build_extension.py``; the manifest and the zip
  are validated), installs it with Blender's ``install-file`` into a throw-away user repository ``cf_pytest`` and
  enables it as ``bl_ext.cf_pytest.curved_fold``. It yields that module and disables it at the end. Because the
  installed copy is what Blender imports, relative-import mistakes and files missing from the zip show up here.
  Use the module it yields (or ``bpy.ops.curved_fold`` / ``bpy.types.Object.curved_fold``) in Blender tests rather
  than ``import curved_fold``: the dev package and the installed copy are different module objects, so their
  classes are not interchangeable (``isinstance`` across them fails).
* ``clean_scene`` (function): ``read_homefile(use_empty=True)`` before the test (~8 ms): empty data, add-on still
  enabled. It yields ``bpy.context.scene``.
* ``extension_zip`` (session): the path of the licence-clean zip the session built.
* ``view3d`` (function, implies ``clean_scene``): ``window/screen/area/region`` of the 3D viewport for
  ``bpy.context.temp_override(**view3d)`` — for operators and panels that need a 3D viewport context.
* ``fixtures_dir`` (session): ``tests/fixtures`` (vendored real crease patterns with their licence and credits).
* ``ext_module(extension, "scene.curves")`` (plain function, ``from .conftest import ext_module``): import a module
  of the installed copy.
* ``backend`` (function, engine tests of the linear algebra): runs the test once with numpy's OpenBLAS routines
  (``core/solve/lapack.py``; skipped where they are not found) and once with the numpy fallback forced.

Never call ``read_factory_settings`` in a test: it disables every add-on (blender-notes §2.1).

``BLENDER_USER_RESOURCES`` is pointed at a fresh temporary folder when this file is imported (before anything
imports ``bpy``) unless the caller already set it (``make test`` does), so no developer preferences or extensions
leak in and nothing is written to ``~/.config/blender``.
"""

from __future__ import annotations

import atexit
import importlib
import importlib.util
import os
import shutil
import sys
import tempfile
from pathlib import Path
from types import ModuleType

import pytest

REPO = Path(__file__).resolve().parents[1]
FIXTURES = Path(__file__).resolve().parent / "fixtures"

REPO_MODULE = "cf_pytest"
"""Module name of the throw-away extension repository the session installs into."""
EXTENSION_ID = "curved_fold"

if "BLENDER_USER_RESOURCES" not in os.environ:
    os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="curved_fold_user_")
    atexit.register(shutil.rmtree, os.environ["BLENDER_USER_RESOURCES"], True)


def load_build_tool() -> ModuleType:
    """Import ``tools/build_extension.py`` (not part of the package, so not importable by name)."""
    name = "curved_fold_build_extension"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, REPO / "tools" / "build_extension.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def extension_zip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The licence-clean zip, built and validated once per session by Blender's builder."""
    tool = load_build_tool()
    return tool.build_clean(tmp_path_factory.mktemp("dist"))


@pytest.fixture(scope="session")
def extension(extension_zip: Path, tmp_path_factory: pytest.TempPathFactory):
    """Install the built zip into a temporary user repository, enable it, yield the enabled module; disable after."""
    import bpy  # noqa: I001 - bpy first: it puts addon_utils and bl_pkg on sys.path
    import addon_utils

    bpy.ops.wm.read_factory_settings(use_empty=True)
    from bl_pkg import bl_extension_cli

    repo_dir = tmp_path_factory.mktemp("extension_repo")
    if extension_repository() is None:
        bpy.context.preferences.extensions.repos.new(
            name="Curved Fold tests", module=REPO_MODULE, custom_directory=str(repo_dir), source="USER"
        )
    rc = bl_extension_cli.cli_extension_handler(["install-file", "-r", REPO_MODULE, "-e", str(extension_zip)])
    module_name = f"bl_ext.{REPO_MODULE}.{EXTENSION_ID}"
    if rc not in (0, None):
        pytest.fail(f"installing {extension_zip} into repo {REPO_MODULE!r} failed with exit code {rc}")
    loaded_default, loaded_state = addon_utils.check(module_name)
    if not loaded_state:
        errors: list[str] = []
        addon_utils.enable(module_name, default_set=True, handle_error=lambda exc: errors.append(repr(exc)))
        if errors or not addon_utils.check(module_name)[1]:
            pytest.fail(f"enabling {module_name} failed: {errors or 'unknown error'}")
    module = sys.modules[module_name]
    try:
        yield module
    finally:
        if addon_utils.check(module_name)[1]:
            addon_utils.disable(module_name, default_set=True)


def extension_repository():
    """The throw-away extension repository (``bpy.types.UserExtensionRepo``) of the session, or ``None``."""
    import bpy

    return next((r for r in bpy.context.preferences.extensions.repos if r.module == REPO_MODULE), None)


@pytest.fixture
def clean_scene(extension):
    """An empty file (``read_homefile(use_empty=True)``) with the extension still enabled; yields the scene."""
    import bpy

    bpy.ops.wm.read_homefile(use_empty=True)
    yield bpy.context.scene


@pytest.fixture
def view3d(clean_scene) -> dict:
    """Keyword arguments for ``bpy.context.temp_override(**view3d)`` that put an operator in the 3D viewport.

    Headless, ``bpy.context.area`` is ``None``, so operators and panels that poll for a 3D viewport need this
    (blender-notes §2.1); the window's VIEW_3D area and its WINDOW region are used. Misspelled keys in
    ``temp_override`` are silently ignored, so build on this dict rather than retyping it.
    """
    import bpy

    window = bpy.context.window_manager.windows[0]
    area = next((a for a in window.screen.areas if a.type == "VIEW_3D"), None)
    if area is None:
        pytest.skip("no VIEW_3D area in the headless window")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return {"window": window, "screen": window.screen, "area": area, "region": region}


def ext_module(extension: ModuleType, name: str) -> ModuleType:
    """Import ``<extension>.<name>`` from the installed copy, e.g. ``ext_module(extension, "scene.curves")``."""
    return importlib.import_module(f"{extension.__name__}.{name}")


@pytest.fixture(params=["lapack", "numpy"])
def backend(request):
    """Run the test with the OpenBLAS routines and again with the numpy fallback forced."""
    from curved_fold.core.solve import lapack

    if request.param == "lapack":
        if lapack.routines() is None:
            pytest.skip("numpy's OpenBLAS with LAPACK/CBLAS not found (the fallback is what runs here)")
        yield request.param
    else:
        with lapack.disabled():
            assert lapack.routines() is None
            yield request.param


@pytest.fixture(scope="session")
def fixtures_dir() -> Path:
    """``tests/fixtures``: the real crease patterns vendored into the repository (always present)."""
    assert FIXTURES.is_dir(), f"vendored fixtures folder {FIXTURES} is missing"
    return FIXTURES


# -- process exit -------------------------------------------------------------------------------------------------
# bpy 4.5 can deadlock in its C++ static destructors at interpreter exit: a background "delayed close" thread waits on
# a condition variable that ~GlobalState() destroys (seen in CI: the 4.5 run printed its summary, then hung for ever
# in pthread_cond_destroy). Once pytest has reported everything, leave the process with os._exit and pytest's own
# exit status, skipping those destructors. Set CURVED_FOLD_NORMAL_EXIT=1 to exit normally (e.g. pytest.main() inside
# a Blender session, where os._exit would end Blender too).
_SESSION: list[pytest.Session] = []


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    _SESSION[:] = [session]


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config: pytest.Config) -> None:
    if "bpy" not in sys.modules or os.environ.get("CURVED_FOLD_NORMAL_EXIT") or not _SESSION:
        return
    status = int(_SESSION[0].exitstatus)
    sys.stdout.flush()
    sys.stderr.flush()
    atexit._run_exitfuncs()  # our own clean-ups (temporary Blender user folder), as a normal exit would
    os._exit(status)
