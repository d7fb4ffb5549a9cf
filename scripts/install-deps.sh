#!/usr/bin/env bash
# Installs every Debian 12 package Regolith needs to build, test and run.
# Idempotent: packages already present are skipped by apt. Needs root (or sudo).
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git clang-format clang-tidy
  # fuzzing (scripts/fuzz.sh, tests/fuzz): clang 14 with libFuzzer and its sanitizer runtimes
  clang libclang-rt-14-dev
  # compiler cache: scripts/test-all.sh reuses objects across runs on one machine
  ccache
  # I/O: HDF5 stores, GDAL import, PROJ (also the projection oracle in tests), libcrypto
  # (SHA-256 of import sources)
  libhdf5-dev hdf5-tools libgdal-dev gdal-bin libproj-dev proj-bin libdeflate-dev libssl-dev
  # the optional ZFP codec of stores: libzfp encodes chunks, the H5Z-ZFP plugin (filter
  # 32013, in HDF5's default plugin directory) decodes them for every HDF5 reader
  libzfp-dev hdf5-filter-plugin-zfp-serial
  # regolith-mpi (tools/mpi, docs/scale.md): MPI coordinates the ranks, each rank writes with the
  # serial HDF5 above (no parallel HDF5 build)
  openmpi-bin libopenmpi-dev
  # maths and rendering: GLM, OpenGL/EGL through Mesa (llvmpipe; clod links libglvnd's
  # libOpenGL from libopengl-dev, no GLX), GLFW windows, PNG
  libglm-dev libegl-dev libgl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri libglfw3-dev libpng-dev
  # a virtual X server for the viewer's window test (xvfb-run needs xauth)
  xvfb xauth
  # /usr/bin/time (wall, CPU and peak RSS of each step of scripts/scale-store.sh, which ctest
  # scale_store_script runs)
  time
  # tests, benchmarks, CLI, JSON
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev
  # Python bindings and Python-side oracles (Debian's interpreter, not PyPI)
  python3 python3-dev pybind11-dev python3-numpy python3-pytest python3-h5py python3-gdal python3-matplotlib python3-pil
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
echo "install-deps: installing ${#missing[@]} missing packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
