#!/bin/sh
# Linear growth of a dark-matter box (COSMOLOGY.md's C10.4 validation run): 64^3 particles in
# 256 Mpc/h (Omega_m 0.3, Omega_Lambda 0.7, Omega_b 0.03 in the transfer function, h 0.6,
# sigma_8 0.9), 2LPT at z = 49, TreePM with a 128^3 mesh, to z = 0; then the power in the
# three longest-wave shells against linear theory, D(a)^2 times the initial power. Two runs:
# seed 1 and its paired partner (the same field, sign reversed), whose mean cancels the
# realisation's own second-order term (Angulo & Pontzen 2016).
#   sh examples/linear_growth/run.sh [-t THREADS]
set -eu
. "$(dirname "$0")/../../scripts/example_prelude.sh"
for member in seed1 inverted; do
  mkdir -p "$member"
  cd "$member"
  flags=""
  [ "$member" = inverted ] && flags="--invert-phases"
  # shellcheck disable=SC2086
  [ -f box.hdf5 ] || "$bin" ic cosmo -n 64 --box 256 --z-start 49 --seed 1 --omega-b 0.03 --hubble 0.6 \
    --sigma-8 0.9 --no-gas $flags -o box.hdf5
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
  softening_dark_matter: 0.16   # 1/25 of the spacing, comoving
  mesh_cells: 128
time_integration:
  dt_max: 1
output:
  directory: run
  scale_factors: [0.25, 0.5]
EOT
  if [ -f run/restart.hdf5 ] && [ ! -f run/snapshot_0003.hdf5 ]; then
    "$bin" run params.yml --restart "$@"
  elif [ ! -f run/snapshot_0003.hdf5 ]; then
    "$bin" run params.yml "$@"
  fi
  cd ..
done
/usr/bin/python3 "$here/plot_linear_growth.py" seed1/run inverted/run
