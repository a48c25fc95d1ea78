#!/bin/sh
# The halo mass function (COSMOLOGY.md's C10.9 validation run): 128^3 dark-matter particles in
# 100 Mpc/h (Omega_m 0.3, Omega_Lambda 0.7, Omega_b 0.03 in the transfer function, h 0.6,
# sigma_8 0.9), 2LPT at z = 49, TreePM with a 256^3 mesh, to z = 0; then friends-of-friends
# groups (b = 0.2) and their mass function against Jenkins et al. (2001) and Sheth & Tormen
# (1999). Resumable: run it again after a kill.
#   sh examples/mass_function/run.sh [-t THREADS]
set -eu
. "$(dirname "$0")/../../scripts/example_prelude.sh"
[ -f box.hdf5 ] || "$bin" ic cosmo -n 128 --box 100 --z-start 49 --seed 1 --omega-b 0.03 --hubble 0.6 \
  --sigma-8 0.9 --no-gas -o box.hdf5
cat > params.yml <<EOT
initial_conditions:
  file: box.hdf5
  periodic: true
cosmology:
  enabled: true
  omega_m: 0.3
  omega_lambda: 0.7
  omega_b: 0.03
  hubble_param: 0.6
  a_end: 1
gravity:
  enabled: true
  softening_dark_matter: 0.03125   # 1/25 of the spacing, comoving
  mesh_cells: 256
time_integration:
  dt_max: 1
output:
  directory: run
  scale_factors: [0.5]
restart:
  every_minutes: 10
EOT
if [ -f run/restart.hdf5 ] && [ ! -f run/snapshot_0002.hdf5 ]; then
  "$bin" run params.yml --restart "$@"
elif [ ! -f run/snapshot_0002.hdf5 ]; then
  "$bin" run params.yml "$@"
fi
[ -f fof.hdf5 ] || "$bin" fof run/snapshot_0002.hdf5 -o fof.hdf5 "$@"
"$bin" mass-function fof.hdf5 --sigma-8 0.9 --omega-b 0.03 -o mass_function.txt
/usr/bin/python3 "$here/plot_mass_function.py" mass_function.txt -o mass_function.png
