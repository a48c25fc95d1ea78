#!/bin/sh
# Zel'dovich's pancake (COSMOLOGY.md C10.3; docs/validation.md, "Comoving runs"): 32^3 gas
# particles in 64 Mpc/h, Einstein-de Sitter, from z = 100 to z = 1.5 (the caustic is at z = 1),
# mesh 32^3, 64 neighbours, MSPH on; once with the paper's viscosity and once with the
# reconstructed one; then the particles against the exact solution at z = 4 and z = 1.5.
#   sh examples/zeldovich_pancake/run.sh [-t THREADS]   (about 2 minutes a run on 2 threads)
set -eu
. "$(dirname "$0")/../../scripts/example_prelude.sh"
[ -f ics.hdf5 ] || /usr/bin/python3 "$here/make_ics.py" 32 ics.hdf5
for viscosity in paper reconstructed; do
  reconstruction=false
  [ "$viscosity" = reconstructed ] && reconstruction=true
  cat > "$viscosity.yml" <<EOT
initial_conditions:
  file: ics.hdf5
  periodic: true
cosmology:
  enabled: true
  omega_m: 1
  omega_lambda: 0
  omega_b: 1
  hubble_param: 1
  a_end: 0.4
gravity:
  enabled: true
  softening_gas: 0.05     # comoving Mpc/h
  mesh_cells: 32
hydro:
  neighbours: 64
  msph: true
  viscosity_reconstruction: $reconstruction
time_integration:
  dt_max: 1
output:
  directory: $viscosity
  redshifts: [4]
EOT
  [ -f "$viscosity/snapshot_0002.hdf5" ] || "$bin" run "$viscosity.yml" -q "$@"
done
/usr/bin/python3 "$here/plot_pancake.py" paper reconstructed "$root/docs/validation/zeldovich_pancake.png"
