#!/bin/sh
# Evrard (1988) adiabatic collapse with self-gravity (G = M = R = 1, u = 0.05): runs at two
# resolutions (-n 8: 2,176 particles; -n 16: 8x as many) to t = 0.8, then plots density,
# radial velocity and entropy profiles of both, and the energy budget of the small one to t = 3.
#   sh examples/evrard/run.sh
set -eu
. "$(dirname "$0")/../../scripts/example_prelude.sh"
for n in 8 16; do
  [ -f "evrard_$n.hdf5" ] || "$bin" ic evrard -n "$n" -o "evrard_$n.hdf5"
  t_end=0.8
  [ "$n" = 8 ] && t_end=3.0
  cat > "params_$n.yml" <<EOT
run:
  t_end: $t_end
initial_conditions:
  file: evrard_$n.hdf5
output:
  directory: run_$n
  delta_time: 0.8
  statistics_every: 10
time_integration:
  dt_max: 0.01
  dt_min: 1.0e-9
hydro:
  msph: false
  neighbours: 50
gravity:
  enabled: true
  G: 1.0
  softening_gas: 0.02
EOT
  [ -f "run_$n/snapshot_0001.hdf5" ] || "$bin" run "params_$n.yml" -t "${THREADS:-2}" -q --overwrite
done
/usr/bin/python3 "$here/plot_evrard.py" run_8/snapshot_0001.hdf5 run_16/snapshot_0001.hdf5 run_8/statistics.txt \
  -o "$root/docs/validation/evrard.png"
