#!/bin/sh
# Dark-matter zooms of several halos of the parent run (after run_parent.sh), each checked
# against the parent by check_zoom.py (M_200, centre, contamination): how well a zoom
# reproduces its parent's halo, over a set of halos rather than one. Resumable.
#   [HALOS="83 96 89"] sh examples/zoom/zoom_set.sh [-t THREADS]
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="$root/build/fountain"
out="$here/output"
[ -f "$out/parent_fof.hdf5" ] || { echo "run examples/zoom/run_parent.sh first" >&2; exit 1; }
cd "$out"
mkdir -p set
# The isolated candidates of COSMOLOGY.md C8.1 in the paper's parent (M_200 in [6e11, 1.5e12]
# Msun/h, no group of half the mass within 2 Mpc/h), the default choice first.
halos=${HALOS:-"83 96 89 91 76 70 109 84 80 56 60 77"}
cosmology="--box 26.6 --z-start 49 --seed 1 --omega-m 0.3 --omega-lambda 0.7 --omega-b 0.03 --hubble 0.6 --sigma-8 0.9"
zoom_softening=$(/usr/bin/python3 -c "print(f'{0.035 * 26.6 / 2 ** 7:.6g}')")
for h in $halos; do
  name=set/h$h
  # shellcheck disable=SC2086
  [ -f "$name.hdf5" ] || "$bin" ic zoom --levels 5 6 7 $cosmology --parent parent/snapshot_0001.hdf5 \
    --groups parent_fof.hdf5 --halo "$h" --no-gas -o "$name.hdf5" > "$name.txt" 2>&1
  cat > "$name.yml" <<EOT
initial_conditions: {file: h$h.hdf5, periodic: true}
cosmology: {enabled: true, omega_m: 0.3, omega_lambda: 0.7, omega_b: 0.03, hubble_param: 0.6, a_end: 1}
gravity: {enabled: true, softening_dark_matter: $zoom_softening, mesh_cells: 128}
time_integration: {dt_max: 1}
output: {directory: h$h}
EOT
  [ -f "$name/snapshot_0001.hdf5" ] || (cd set && "$bin" run "h$h.yml" -q "$@" > "h$h.run.txt" 2>&1)
  [ -f "${name}_fof.hdf5" ] || "$bin" fof "$name/snapshot_0001.hdf5" -o "${name}_fof.hdf5" "$@" > /dev/null
  /usr/bin/python3 "$here/check_zoom.py" parent_fof.hdf5 "${name}_fof.hdf5" "$name/snapshot_0001.hdf5" "$name.txt" || true
done
