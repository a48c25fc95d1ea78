#!/bin/sh
# A uniform expanding box (COSMOLOGY.md C10.2; docs/validation.md, "Comoving runs"): 32^3 gas
# particles on a lattice in 64 Mpc/h at rest, 1e4 K at a = 1/64, gravity (TreePM, mesh 32^3) and
# hydro, to a = 1, in Einstein-de Sitter and in flat LCDM (0.3, 0.7). Nothing may change but the
# temperature, which falls as a^-2.
#   sh examples/constant_volume/run.sh [-t THREADS]   (a few minutes a run on 2 threads)
set -eu
. "$(dirname "$0")/../../scripts/example_prelude.sh"
for model in eds lcdm; do
  if [ $model = eds ]; then om=1; ol=0; else om=0.3; ol=0.7; fi
  [ -f "$model.hdf5" ] || /usr/bin/python3 "$here/make_ics.py" 32 $om $ol "$model.hdf5"
  cat > "$model.yml" <<EOT
initial_conditions:
  file: $model.hdf5
  periodic: true
cosmology:
  enabled: true
  omega_m: $om
  omega_lambda: $ol
  omega_b: $om
  hubble_param: 1
  a_end: 1
gravity:
  enabled: true
  softening_gas: 0.1      # comoving Mpc/h: 0.05 of the spacing
  mesh_cells: 32
hydro:
  neighbours: 32
  neighbours_tolerance: 1e-6
time_integration:
  dt_max: 1
  max_dln_a: 0.01
output:
  directory: $model
  scale_factors: [0.03125, 0.0625, 0.125, 0.25, 0.5]
EOT
  [ -f "$model/snapshot_0006.hdf5" ] || "$bin" run "$model.yml" -q "$@"
done
/usr/bin/python3 "$here/plot_constant_volume.py" eds lcdm "$root/docs/validation/constant_volume.png"
