#!/usr/bin/env bash
# Installs the Debian 12 packages phantasm builds and tests with. Idempotent: when every
# package is already installed it does nothing (no apt-get update, no network).
set -euo pipefail

packages=(
  build-essential cmake pkg-config ninja-build clang-format
  clang-14 libclang-rt-14-dev libomp-14-dev llvm-14 lld
  libeigen3-dev
  libsuitesparse-dev libopenblas0-openmp libopenblas-openmp-dev
  libopenvdb-dev libboost-iostreams-dev libtbb-dev
  libcgal-dev
  libvtk9-dev
  libhdf5-dev
  libnifti2-dev libniftiio-dev libznz-dev libnifticdf-dev nifti-bin
  libfftw3-dev
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy python3-scipy python3-yaml python3-nibabel python3-h5py
  python3-matplotlib python3-openvdb python3-vtk9
  elastix snakemake
  mrtrix3 python3-dipy
  slurm-wlm munge
  zlib1g-dev libdeflate-dev libpng-dev
  libtcmalloc-minimal4
  mricron-data
  chromium
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi

# CHOLMOD's supernodal factorization calls BLAS/LAPACK through Debian's alternatives. The
# OpenMP build of OpenBLAS shares the OpenMP runtime with our local step instead of starting
# its own pthread pool that competes for the same two cores. Its libblas.so.3 loads
# libopenblas.so.0, a third alternative: left at the pthread build, that pool (and its
# sched_yield spinning) comes back and the 10k-vertex global solve takes twice as long.
select_openmp_blas() {
  local arch_dir=/usr/lib/x86_64-linux-gnu
  [ "$(uname -m)" = x86_64 ] || return 0
  for lib in libblas.so.3 liblapack.so.3 libopenblas.so.0; do
    local want="$arch_dir/openblas-openmp/$lib"
    [ -e "$want" ] || continue
    if [ "$(readlink -f "$arch_dir/$lib")" != "$(readlink -f "$want")" ]; then
      "${sudo_cmd[@]}" update-alternatives --set "$lib-x86_64-linux-gnu" "$want" >/dev/null
    fi
  done
}

# The BIDS validator the test suite runs on every dataset layout (tests/io/CMakeLists.txt):
# the npm package, version 1 (the one most users run), under /usr/local. Node.js and npm come
# from Debian unless a node is already installed (a NodeSource node brings its own npm).
bids_validator_version=1.15.0
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  for p in nodejs npm; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
      missing+=("$p")
    fi
  done
fi

install_bids_validator() {
  # The installed version from its package.json (starting node to ask takes seconds).
  local manifest=/usr/local/lib/node_modules/bids-validator/package.json
  if [ -x /usr/local/bin/bids-validator ] && [ -f "$manifest" ] &&
    grep -q "\"version\": \"$bids_validator_version\"" "$manifest"; then
    return 0
  fi
  echo "phantasm: installing bids-validator $bids_validator_version (npm) under /usr/local" >&2
  "${sudo_cmd[@]}" npm install --global --prefix /usr/local --no-audit --no-fund \
    "bids-validator@$bids_validator_version" >&2
}

if [ ${#missing[@]} -eq 0 ]; then
  select_openmp_blas
  install_bids_validator
  exit 0
fi

echo "phantasm: installing ${#missing[@]} missing Debian packages: ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update
"${sudo_cmd[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
select_openmp_blas
install_bids_validator
