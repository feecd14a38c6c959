#!/usr/bin/env bash
# Set up everything dolfinx_fretting needs on Debian bookworm (run as root), idempotently.
#
#   * Debian packages: DOLFINx 0.5.2 (python3-dolfinx), gmsh, h5py, OpenBLAS; libegl1 and libgl1-mesa-dri,
#     with which VTK's wheel renders the pyvista pictures off screen (EGL, Mesa's software rasteriser).
#   * A venv (.venv) made from /usr/bin/python3 with --system-site-packages, so it sees DOLFINx.
#   * The package in editable mode with its extras (default: test,pictures), numpy pinned to Debian's build
#     (constraints.txt): pip would otherwise pull numpy 2.x into the venv and shadow the numpy DOLFINx is
#     compiled against. The pictures extra (pyvista, vtk) adds ~690 MB to the venv (vtk: 565 MB) and
#     took 10-17 s to install here from a warm package cache.
#
# Quick when everything is already there: each step checks first. Used by ./tasks.sh, .ci/run and the
# Dockerfile, so there is one copy of the install steps.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$here"
extras=${DOLFINX_FRETTING_EXTRAS:-test,pictures}

apt_pkgs=(python3-dolfinx python3-gmsh python3-h5py python3-venv python3-pip python3-scipy libopenblas0-pthread
          openmpi-bin git libegl1 libgl1-mesa-dri)
missing=()
for p in "${apt_pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

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
