#!/bin/sh
# Makes the ICs, runs the blast and plots density against radius with the exact solution.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$here"
"$root/build/fountain" ic sedov -n "${RESOLUTION:-24}" -o sedov.hdf5
"$root/build/fountain" run params.yml --overwrite
/usr/bin/python3 "$here/plot_sedov.py" output/snapshot_0002.hdf5 -o output/sedov_density.png
