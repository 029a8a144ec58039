#!/usr/bin/env bash
# One-command development set-up for Curved Fold (called by `make setup`; safe to run again).
#
# * Debian libraries the bpy wheel links against (X11/EGL/GL; Mesa for Workbench software GL) — installed only if
#   missing, with apt-get when running as root, otherwise a clear message saying what to run.
# * .venv      : Python 3.11 + bpy 5.0.1 + triangle + numpy + pytest + hypothesis + matplotlib + ruff
# * .venv-4.5  : Python 3.11 + bpy 4.5.15 (the LTS) + triangle + numpy + pytest + hypothesis + matplotlib (bench smoke test)
# * in each venv, `import curved_fold` works: the repository root IS the package, whatever the clone's folder is
#   called, so <venv>/links/curved_fold is a symlink to the root and a .pth file puts <venv>/links on sys.path.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PYTHON="${PYTHON:-}"

APT_PACKAGES=(libx11-6 libxi6 libxfixes3 libxrender1 libxkbcommon0 libsm6 libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri)
MAIN_REQUIREMENTS=(bpy==5.0.1 numpy==1.26.4 triangle==20250106 pytest hypothesis matplotlib ruff)
LTS_REQUIREMENTS=(bpy==4.5.15 numpy==1.26.4 triangle==20250106 pytest hypothesis matplotlib)

say() { printf 'setup: %s\n' "$*"; }

find_python() {
    # bpy 4.5/5.0 wheels exist for CPython 3.11 only.
    local candidate
    for candidate in "$PYTHON" python3.11 python3; do
        [ -n "$candidate" ] || continue
        if command -v "$candidate" >/dev/null 2>&1 &&
            "$candidate" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
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
    # make_venv <dir> <requirements...>
    local venv="$1"
    shift
    if [ ! -x "$venv/bin/python" ]; then
        local python
        if ! python="$(find_python)"; then
            say "ERROR: Python 3.11 not found (bpy 4.5 and 5.0 exist only for CPython 3.11); set PYTHON=/path/to/python3.11"
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
make_venv "$ROOT/.venv" "${MAIN_REQUIREMENTS[@]}"
make_venv "$ROOT/.venv-4.5" "${LTS_REQUIREMENTS[@]}"
say "done"
