#!/bin/sh
# Makes the Gresho vortex ICs, runs to t = 1 and plots v_phi(r) against the initial profile.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$here"
"$root/build/fountain" ic gresho -n "${RESOLUTION:-24}" -o gresho.hdf5
"$root/build/fountain" run params.yml --overwrite -q
/usr/bin/python3 "$here/plot_gresho.py" output/snapshot_0001.hdf5 -o output/gresho.png
