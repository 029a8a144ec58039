#!/usr/bin/env bash
# One-command development set-up for Curved Fold (called by `make setup`; safe to run again).
#
# * Debian libraries the bpy wheel links against (X11/EGL/GL; Mesa for Workbench software GL) — installed only if
#   missing, with apt-get when running as root, otherwise a clear message saying what to run.
# * .venv      : Python 3.11 + bpy 5.0.1 + triangle + numpy + pytest + hypothesis + matplotlib + ruff
# * .venv-4.5  : Python 3.11 + bpy 4.5.15 (the LTS) + triangle + numpy + pytest + hypothesis + matplotlib (bench smoke test)
# * .venv-5.2  : Python 3.13 + bpy 5.2.3 (the current LTS) + numpy 2 + triangle + pytest + hypothesis + matplotlib
# * in each venv, `import curved_fold` works: the repository root IS the package, whatever the clone's folder is
#   called, so <venv>/links/curved_fold is a symlink to the root and a .pth file puts <venv>/links on sys.path.
# * tools/node_modules/gltf-validator: the Khronos glTF validator from npm, when npm is there (a test runs it)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PYTHON="${PYTHON:-}"       # a Python 3.11 to use for .venv and .venv-4.5 (optional)
PYTHON313="${PYTHON313:-}" # a Python 3.13 to use for .venv-5.2 (optional)

APT_PACKAGES=(libx11-6 libxi6 libxfixes3 libxrender1 libxkbcommon0 libsm6 libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri)
MAIN_REQUIREMENTS=(bpy==5.0.1 numpy==1.26.4 triangle==20250106 pytest hypothesis matplotlib ruff)
LTS_REQUIREMENTS=(bpy==4.5.15 numpy==1.26.4 triangle==20250106 pytest hypothesis matplotlib)
LTS52_REQUIREMENTS=(bpy==5.2.3 numpy==2.5.5 triangle==20250106 pytest hypothesis matplotlib)

say() { printf 'setup: %s\n' "$*"; }

find_python() {
    # find_python <major.minor> [explicit]: print the path of a working CPython <major.minor>, or fail.
    # bpy 4.5/5.0 wheels exist for CPython 3.11 only, bpy 5.1/5.2 for 3.13 only. Each candidate is run, not just
    # looked up: a pyenv shim for a version that is installed but not selected exists on PATH and fails when run,
    # so pyenv's own versions are tried last, by their real paths.
    local want="$1" explicit="${2:-}" candidate root version
    local check="import sys; sys.exit(sys.version_info[:2] != tuple(map(int, '$want'.split('.'))))"
    local candidates=("$explicit" "python$want" python3)
    if command -v pyenv >/dev/null 2>&1 && root="$(pyenv root 2>/dev/null)"; then
        while read -r version; do
            candidates+=("$root/versions/$version/bin/python$want")
        done < <(pyenv versions --bare 2>/dev/null | grep -E "^$want(\.[0-9]+)?$" | sort -rV)
    fi
    for candidate in "${candidates[@]}"; do
        [ -n "$candidate" ] || continue
        if command -v "$candidate" >/dev/null 2>&1 && "$candidate" -c "$check" 2>/dev/null; then
            command -v "$candidate"
            return 0
        fi
    done
    return 1
}

system_libraries() {
    if ! command -v dpkg-query >/dev/null 2>&1; then
        say "not a Debian/Ubuntu system: make sure X11, EGL and GL libraries are installed (bpy needs them)"
        return 0
    fi
    local missing=() pkg
    for pkg in "${APT_PACKAGES[@]}"; do
        if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
            missing+=("$pkg")
        fi
    done
    if [ ${#missing[@]} -eq 0 ]; then
        say "system libraries for bpy: present"
        return 0
    fi
    if [ "$(id -u)" -eq 0 ]; then
        say "installing system libraries for bpy: ${missing[*]}"
        apt-get update
        DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
    else
        say "ERROR: bpy needs these Debian packages, which are missing: ${missing[*]}"
        say "run:  sudo apt-get update && sudo apt-get install -y ${missing[*]}   then  make setup  again"
        exit 1
    fi
}

make_venv() {
    # make_venv <dir> <python version> <why that version> <requirements...>
    local venv="$1" want="$2" why="$3"
    shift 3
    if [ ! -x "$venv/bin/python" ]; then
        local python explicit="$PYTHON" var=PYTHON
        if [ "$want" = 3.13 ]; then explicit="$PYTHON313" var=PYTHON313; fi
        if ! python="$(find_python "$want" "$explicit")"; then
            say "ERROR: Python $want not found ($why); install it (pyenv install $want, or your distribution's python$want package) or set $var=/path/to/python$want"
            exit 1
        fi
        say "creating $venv with $python"
        "$python" -m venv "$venv"
    fi
    say "installing into $venv: $*"
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "$@"
    # curved_fold importable in the venv: symlink + .pth (idempotent).
    mkdir -p "$venv/links"
    ln -sfn "$ROOT" "$venv/links/curved_fold"
    local site
    site="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
    printf '%s\n' "$venv/links" >"$site/curved_fold_dev.pth"
    "$venv/bin/python" -c 'import curved_fold, bpy; print("setup:", "'"$venv"'", "bpy", bpy.app.version_string, "curved_fold from", curved_fold.__path__[0])'
}

system_libraries
PY311_WHY="bpy 4.5 and 5.0 exist only for CPython 3.11"
make_venv "$ROOT/.venv" 3.11 "$PY311_WHY" "${MAIN_REQUIREMENTS[@]}"
make_venv "$ROOT/.venv-4.5" 3.11 "$PY311_WHY" "${LTS_REQUIREMENTS[@]}"
make_venv "$ROOT/.venv-5.2" 3.13 "bpy 5.1 and 5.2 exist only for CPython 3.13" "${LTS52_REQUIREMENTS[@]}"

# The Khronos glTF validator (npm) for tests/test_export_files.py: the real client checks our .glb files. Optional:
# without node/npm the test skips and says why.
GLTF_VALIDATOR=gltf-validator@2.0.0-dev.3.10
if [ -f "$ROOT/tools/node_modules/gltf-validator/package.json" ]; then
    say "glTF validator: present"
elif command -v npm >/dev/null 2>&1; then
    say "installing $GLTF_VALIDATOR into tools/node_modules"
    npm install --prefix "$ROOT/tools" --no-save --no-package-lock --no-audit --no-fund "$GLTF_VALIDATOR" >/dev/null ||
        say "glTF validator not installed: tests/test_export_files.py skips its validator test"
else
    say "npm not found: tests/test_export_files.py skips its glTF validator test"
fi
say "done"
