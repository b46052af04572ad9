#!/usr/bin/env bash
# Installs every Debian package PBA needs to build, run and test.
# Idempotent: a quick no-op when everything is already present.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config git
  libeigen3-dev libsuitesparse-dev libopenblas-dev
  libhdf5-dev libpng-dev zlib1g-dev libnifti2-dev
  libcgal-dev libgmp-dev libmpfr-dev
  libgrpc++-dev libgrpc-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libsqlite3-dev
  libpetsc-real-dev libopenmpi-dev openmpi-bin
  libyaml-cpp-dev libcli11-dev libspdlog-dev libfmt-dev libtinyxml2-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  calculix-ccx
  python3-meshio python3-h5py python3-paraview
  python3 universal-ctags
  libssl-dev
  gnuplot-nox time
  openssl
  mricron-data
  slurmctld slurmd slurm-client munge
  libcpp-httplib-dev libjs-three libjs-chart.js
  chromium chromium-driver python3-selenium
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "deps: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "deps: done"
