"""The layout keeps its promises, checked statically on the source (every import, also those inside functions).

* ``core/`` is the paper's pipeline in stages, and data flows one way: ``pattern`` (§3.1) → ``mesh`` (§3.2–3.3) →
  ``solve`` → ``metrics`` → ``io`` (readers give patterns, writers take meshes and results) → ``pipeline``. No module
  imports a later stage.
* ``core`` never imports the Blender layers nor touches ``bpy.context``; the Blender layers point one way:
  ``panels`` → ``operators`` → ``scene`` → ``core``; the command line (``cli``) is a front door beside ``operators``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = "curved_fold"

CORE_STAGES = ("pattern", "mesh", "solve", "metrics", "io", "pipeline")
"""The engine's stages in the order data flows through them (``core/<stage>/`` or ``core/<stage>.py``)."""

LAYER_MAY_IMPORT = {
    "core": {"core"},
    "scene": {"core", "scene"},
    "operators": {"core", "scene", "operators"},
    "panels": {"core", "scene", "operators", "panels"},
    "cli": {"core", "scene", "cli"},
}


def _module_name(path: Path) -> str:
    rel = path.relative_to(REPO).with_suffix("")
    parts = [PACKAGE, *rel.parts]
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> list[tuple[int, str]]:
    """Absolute names of every module ``path`` imports (``from x import y`` yields ``x.y`` as well as ``x``)."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    out: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            out.append((node.lineno, target))
            out += [(node.lineno, f"{target}.{alias.name}") for alias in node.names]
    return out


def _sources(layer: str) -> list[Path]:
    root = REPO / layer
    return sorted(root.rglob("*.py")) if root.is_dir() else [root.with_suffix(".py")]


def _layer_of(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[0] == PACKAGE else None


def _stage_of(module: str) -> int | None:
    parts = module.split(".")
    if len(parts) > 2 and parts[:2] == [PACKAGE, "core"] and parts[2] in CORE_STAGES:
        return CORE_STAGES.index(parts[2])
    return None


def test_every_core_module_belongs_to_a_stage():
    loose = [p.name for p in (REPO / "core").glob("*.py") if p.stem not in ("__init__", *CORE_STAGES)]
    assert not loose, f"modules outside the pipeline's stages: {loose}"
    for stage in CORE_STAGES:
        path = REPO / "core" / stage
        assert path.is_dir() or path.with_suffix(".py").is_file(), stage
        if path.is_dir():
            doc = ast.get_docstring(ast.parse((path / "__init__.py").read_text(encoding="utf-8")))
            assert doc and "in:" in doc.lower() and "out:" in doc.lower(), (
                f"core/{stage}/__init__.py says what comes in/out"
            )


@pytest.mark.parametrize("layer", sorted(LAYER_MAY_IMPORT))
def test_layers_point_one_way(layer):
    allowed = LAYER_MAY_IMPORT[layer]
    bad = []
    for path in _sources(layer):
        for line, module in _imports(path):
            target = _layer_of(module)
            if target in LAYER_MAY_IMPORT and target not in allowed:
                bad.append(f"{path.relative_to(REPO)}:{line} imports {module}")
    assert not bad, "\n".join(bad)


def test_core_stages_import_only_earlier_stages():
    bad = []
    for path in _sources("core"):
        own = _stage_of(_module_name(path))
        if own is None:
            continue
        for line, module in _imports(path):
            stage = _stage_of(module)
            if stage is not None and stage > own:
                bad.append(f"{path.relative_to(REPO)}:{line} ({CORE_STAGES[own]}) imports {module} (later stage)")
    assert not bad, "\n".join(bad)


def test_core_never_touches_the_scene():
    bad = []
    for path in _sources("core"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "bpy":
                if node.attr in ("context", "data", "ops"):
                    bad.append(f"{path.relative_to(REPO)}:{node.lineno} bpy.{node.attr}")
    assert not bad, f"core modules touching Blender's scene data: {bad}"


def test_the_checker_sees_a_violation(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The rules above can fail: in a copy of ``core/``, a pattern module importing the solver is caught."""
    import shutil

    shutil.copytree(REPO / "core", tmp_path / "core", ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "core" / "pattern" / "probe.py").write_text("from ..solve import solver\n", encoding="utf-8")
    monkeypatch.setitem(globals(), "REPO", tmp_path)
    with pytest.raises(AssertionError, match=r"probe.py:1 \(pattern\) imports curved_fold.core.solve"):
        test_core_stages_import_only_earlier_stages()
