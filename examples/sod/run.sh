#!/bin/sh
# Makes the Sod ICs, runs to t = 0.2 and plots density, velocity and pressure against x
# with the exact Riemann solution.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$here"
"$root/build/fountain" ic sod -n "${RESOLUTION:-32}" -o sod.hdf5
"$root/build/fountain" run params.yml --overwrite -q
/usr/bin/python3 "$here/plot_sod.py" output/snapshot_0001.hdf5 -o output/sod.png
