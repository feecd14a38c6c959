#!/usr/bin/env bash
# Set up everything dolfinx_fretting needs on Debian bookworm (run as root), idempotently, for one of two
# stacks:
#
#   scripts/setup.sh [debian]     (default) DOLFINx 0.5.2 from Debian -> .venv
#   scripts/setup.sh current      today's DOLFINx (0.11) from the dolfinx-solver-real wheel -> .venv-current
#   (or DOLFINX_FRETTING_STACK=current scripts/setup.sh)
#
# debian:
#   * Debian packages: DOLFINx 0.5.2 (python3-dolfinx), gmsh, h5py, OpenBLAS; libegl1 and libgl1-mesa-dri,
#     with which VTK's wheel renders the pyvista pictures off screen (EGL, Mesa's software rasteriser).
#   * A venv (.venv) made from /usr/bin/python3 with --system-site-packages, so it sees DOLFINx.
#   * The package in editable mode with its extras (default: test,pictures,docs), numpy pinned to Debian's
#     build (constraints.txt): pip would otherwise pull numpy 2.x into the venv and shadow the numpy DOLFINx
#     is compiled against. The pictures extra (pyvista, vtk) adds ~690 MB to the venv (vtk: 565 MB) and
#     took 10-17 s to install here from a warm package cache. The docs extra (Sphinx, MyST, jupytext, furo;
#     ~80 MB with their dependencies) builds the API reference (./tasks.sh docs, tests/test_docs.py).
# current:
#   * A venv (.venv-current) from Python 3.12 (the wheel needs >= 3.12; bookworm has none, pyenv's is used:
#     `command -v python3.12`, else pyenv's newest 3.12, or DOLFINX_FRETTING_PYTHON312=/path/to/python3.12).
#   * dolfinx-solver-real (DOLFINx 0.11, PETSc/petsc4py 3.25 with MUMPS, MPICH and its mpiexec in
#     .venv-current/bin), gmsh, h5py and the package in editable mode with the extras test,pictures (the
#     API reference is built on the debian stack), every version pinned in constraints-current.txt
#     (numpy 2). A C compiler for the form compiler's JIT (gcc).
#     About 1 GB; ~1-2 minutes the first time.
#
# Quick when everything is already there: each step checks first. Used by ./tasks.sh, .ci/run and the
# Dockerfile, so there is one copy of the install steps.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$here"
extras=${DOLFINX_FRETTING_EXTRAS:-test,pictures,docs}
stack=${1:-${DOLFINX_FRETTING_STACK:-debian}}

missing_debian_packages() {
  local p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || echo "$p"
  done
}

install_debian_packages() {
  local missing
  missing=($(missing_debian_packages "$@"))
  if [ ${#missing[@]} -gt 0 ]; then
    echo "[setup] installing Debian packages: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
}

# A Python 3.12 that really runs (pyenv's shim exists even when 3.12 is not the selected version).
find_python312() {
  local cand
  for cand in "${DOLFINX_FRETTING_PYTHON312:-}" "$(command -v python3.12 || true)"; do
    if [ -n "$cand" ] && "$cand" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 12))' >/dev/null 2>&1; then
      echo "$cand"; return 0
    fi
  done
  local root
  root=$(pyenv root 2>/dev/null || echo "${PYENV_ROOT:-$HOME/.pyenv}")  # pyenv's folder, on PATH or not
  for cand in $(ls -d "$root"/versions/3.12*/bin/python3.12 2>/dev/null | sort -V -r); do
    if "$cand" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 12))' >/dev/null 2>&1; then
      echo "$cand"; return 0
    fi
  done
  return 1
}

setup_current() {
  install_debian_packages gcc libc6-dev git libegl1 libgl1-mesa-dri
  local extras=${DOLFINX_FRETTING_EXTRAS:-test,pictures}
  local venv=.venv-current
  if [ ! -x "$venv/bin/python" ]; then
    local py
    if ! py=$(find_python312); then
      echo "[setup] current stack: no Python 3.12 found (tried \$DOLFINX_FRETTING_PYTHON312, python3.12 on PATH," \
           "pyenv's versions 3.12*); the dolfinx-solver-real wheel needs Python >= 3.12" >&2
      return 1
    fi
    echo "[setup] creating $venv from $py"
    "$py" -m venv "$venv"
  fi
  local stamp="$venv/.dolfinx_fretting-installed"
  local want
  want=$(cat pyproject.toml constraints-current.txt | sha256sum | cut -d' ' -f1)-$extras
  if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    echo "[setup] installing dolfinx-solver-real and dolfinx_fretting[$extras] into $venv"
    "$venv/bin/python" -m pip install -q --disable-pip-version-check -c constraints-current.txt \
      dolfinx-solver-real gmsh h5py -e ".[$extras]"
    echo "$want" > "$stamp"
  fi
}

case "$stack" in
  debian|default) ;;
  current)
    setup_current
    exit ;;
  *)
    echo "usage: scripts/setup.sh [debian|current]  (or DOLFINX_FRETTING_STACK=...); got '$stack'" >&2
    exit 2 ;;
esac

apt_pkgs=(python3-dolfinx python3-gmsh python3-h5py python3-venv python3-pip python3-scipy libopenblas0-pthread
          openmpi-bin git libegl1 libgl1-mesa-dri)
install_debian_packages "${apt_pkgs[@]}"

if [ ! -x .venv/bin/python ]; then
  echo "[setup] creating .venv from /usr/bin/python3 (--system-site-packages)"
  /usr/bin/python3 -m venv --system-site-packages .venv
fi

# Re-install only when the project metadata changed since the last install.
stamp=.venv/.dolfinx_fretting-installed
want=$(cat pyproject.toml constraints.txt | sha256sum | cut -d' ' -f1)-$extras
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "[setup] installing dolfinx_fretting[$extras] into .venv"
  .venv/bin/python -m pip install -q --disable-pip-version-check -c constraints.txt -e ".[$extras]"
  echo "$want" > "$stamp"
fi
