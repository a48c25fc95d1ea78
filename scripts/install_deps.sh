#!/bin/sh
# Installs, from Debian's packages, whatever Fountain needs to build, test and plot.
set -eu
pkgs="cmake ninja-build g++ pkg-config libtbb-dev libhdf5-dev libopenmpi-dev openmpi-bin libfmt-dev
libyaml-cpp-dev libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev libfftw3-dev libfftw3-mpi-dev libmetis-dev libboost-dev
python3-numpy python3-h5py python3-matplotlib python3-yt"
missing=""
for p in $pkgs; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "installing:$missing"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  # shellcheck disable=SC2086
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing > /dev/null
fi
