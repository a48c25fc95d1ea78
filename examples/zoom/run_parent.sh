#!/bin/sh
# The paper's cosmological set-up (COSMOLOGY.md C11.2), first half: the dark-matter parent run
# (64^3 particles in 26.6 Mpc/h, the blocks of the zoom's level-7 field, z = 49 to 0), its
# friends-of-friends halos, and the zoom's initial conditions on the isolated halo nearest
# 1e12 Msun/h: level-7 gas and dark matter in the traced region (about 7,440 particles per
# species), level 6 around it, level 5 elsewhere; the same at masses / 100 (the paper's
# MFB/100); and a dark-matter-only version, run to z = 0 to check that it reproduces the
# parent's halo (check_zoom.py; CHECK=0 skips it). Resumable: a killed run goes on from
# its restart file, finished steps are skipped.
# LEVELS="4 5 6" makes the same at an eighth of the mass resolution (in output_4_5_6/, a
# high-resolution target of 6300 / 8 per species).
#   [LEVELS="5 6 7"] sh examples/zoom/run_parent.sh [-t THREADS]
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="$root/build/fountain"
[ -x "$bin" ] || sh "$root/scripts/build.sh"
levels=${LEVELS:-5 6 7}
# shellcheck disable=SC2086
set -- $levels "$@"
l0=$1 lp=$2 lmax=$3
shift 3
out="$here/output"
[ "$levels" = "5 6 7" ] || out="$here/output_${l0}_${lp}_${lmax}"
mkdir -p "$out"
cd "$out"
py=/usr/bin/python3
# Softenings 0.035 of each level's spacing (comoving); the high-resolution target scaled with
# the finest level's cell mass.
parent_softening=$($py -c "print(f'{0.035 * 26.6 / 2 ** $lp:.6g}')")
zoom_softening=$($py -c "print(f'{0.035 * 26.6 / 2 ** $lmax:.6g}')")
target=$($py -c "print(round(6300 / 8 ** (7 - $lmax)))")
cosmology="--box 26.6 --z-start 49 --seed 1 --omega-m 0.3 --omega-lambda 0.7 --omega-b 0.03 --hubble 0.6 --sigma-8 0.9"
# shellcheck disable=SC2086
[ -f parent_ics.hdf5 ] || "$bin" ic zoom --levels $levels $cosmology -o parent_ics.hdf5
run() {  # run NAME ICS SOFTENING [OPTIONS...]
  name=$1 ics=$2 softening=$3
  shift 3
  cat > "$name.yml" <<EOT
initial_conditions: {file: $ics, periodic: true}
cosmology: {enabled: true, omega_m: 0.3, omega_lambda: 0.7, omega_b: 0.03, hubble_param: 0.6, a_end: 1}
gravity: {enabled: true, softening_dark_matter: $softening, mesh_cells: 128}
time_integration: {dt_max: 1}
output: {directory: $name}
restart: {every_minutes: 10}
EOT
  if [ -f "$name/restart.hdf5" ] && [ ! -f "$name/snapshot_0001.hdf5" ]; then
    "$bin" run "$name.yml" --restart -q "$@"
  elif [ ! -f "$name/snapshot_0001.hdf5" ]; then
    "$bin" run "$name.yml" -q "$@"
  fi
}
threads="$*"
# shellcheck disable=SC2086
run parent parent_ics.hdf5 "$parent_softening" $threads
[ -f parent_fof.hdf5 ] || "$bin" fof parent/snapshot_0001.hdf5 -o parent_fof.hdf5 $threads
# shellcheck disable=SC2086
[ -f zoom_ics.hdf5 ] || "$bin" ic zoom --levels $levels $cosmology --parent parent/snapshot_0001.hdf5 \
  --groups parent_fof.hdf5 --target $target -o zoom_ics.hdf5 2>&1 | tee zoom_ics.txt
# shellcheck disable=SC2086
[ -f zoom_dm_ics.hdf5 ] || "$bin" ic zoom --levels $levels $cosmology --parent parent/snapshot_0001.hdf5 \
  --groups parent_fof.hdf5 --target $target --no-gas -o zoom_dm_ics.hdf5 2>&1 | tee zoom_dm_ics.txt
# The paper's MFB/100 (COSMOLOGY.md C11.3): the same zoom at masses / 100.
# shellcheck disable=SC2086
[ -f zoom_mfb100_ics.hdf5 ] || "$bin" ic zoom --levels $levels $cosmology --parent parent/snapshot_0001.hdf5 \
  --groups parent_fof.hdf5 --target $target --mass-scale 0.01 -o zoom_mfb100_ics.hdf5
# The dark-matter zoom (skipped with CHECK=0): the heavier particles' softenings scaled by m^(1/3).
[ "${CHECK:-1}" = 1 ] || exit 0
# shellcheck disable=SC2086
run zoom_dm zoom_dm_ics.hdf5 "$zoom_softening" $threads
[ -f zoom_dm_fof.hdf5 ] || "$bin" fof zoom_dm/snapshot_0001.hdf5 -o zoom_dm_fof.hdf5 $threads
/usr/bin/python3 "$here/check_zoom.py" parent_fof.hdf5 zoom_dm_fof.hdf5 zoom_dm/snapshot_0001.hdf5 zoom_dm_ics.txt
