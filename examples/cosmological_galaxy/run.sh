#!/bin/sh
# The paper's cosmological runs (Marri & White 2003, section 3.4, Figs 6-8; COSMOLOGY.md C11):
# SPH (R01), MSPH (R02), MSPH+MFB (R04) and MFB/100 (R04 on the zoom scaled to masses / 100),
# from the zoom initial conditions of examples/zoom/run_parent.sh, to z = 0, with HOP groups of
# the baryons at every output and the figures (fig6.png, fig7.png, fig8.png, claims.md).
#   LEVELS="4 5 6" (default): an eighth of the paper's mass resolution, the user guide's example;
#   LEVELS="5 6 7": the paper's (7,440 particles per species in the high-resolution region).
#   MODE=paper: the paper's step bounds (dt in [1e-8, 1e-6] t_U, no limiter); default: Fountain's.
# Resumable: run it again after a kill; finished runs and catalogues are kept.
#   [LEVELS=...] [MODE=...] [RUNS="SPH MSPH MFB MFB100"] sh examples/cosmological_galaxy/run.sh [-t THREADS]
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="$root/build/fountain"
[ -x "$bin" ] || sh "$root/scripts/build.sh"
py=/usr/bin/python3
levels=${LEVELS:-4 5 6}
mode=${MODE:-default}
# shellcheck disable=SC2086
set -- $levels "$@"
lmax=$3
shift 3
LEVELS="$levels" CHECK=0 sh "$root/examples/zoom/run_parent.sh" "$@"
zoom="$root/examples/zoom/output"
[ "$levels" = "5 6 7" ] || zoom="$root/examples/zoom/output_$(echo "$levels" | tr ' ' _)"
out="$here/output_$(echo "$levels" | tr ' ' _)_$mode"
mkdir -p "$out"
# Outputs: z = 20, 15, 12, then equally spaced in cosmic time from z = 10 to 0 (160 at the
# paper's resolution, 40 for the reduced set).
count=40
[ "$lmax" -lt 7 ] || count=160
outputs=$($py "$here/output_times.py" "$count")
# The paper's softenings at level 7 (comoving DM 12, gas 6 kpc/h; physical at most 6 and 3),
# twice as long per level below; the mesh 128^3 (64^3 for the reduced set).
scale=$($py -c "print(2 ** (7 - $lmax))")
mesh=$($py -c "print(128 if $lmax >= 7 else 64)")
case $mode in
  default) steps="dt_max: 1, dt_min: 1.0e-13, timestep_limiter: true" ;;
  paper) steps="dt_max: 1.0e-6, dt_min: 1.0e-8, timestep_limiter: false" ;;
  *) echo "unknown MODE $mode (default or paper)" >&2; exit 2 ;;
esac
for run in ${RUNS:-SPH MSPH MFB MFB100}; do
  msph=true eps=0.4 ics="$zoom/zoom_ics.hdf5" s=1
  case $run in
    SPH) msph=false eps=0 ;;
    MSPH) eps=0 ;;
    MFB) ;;
    MFB100) ics="$zoom/zoom_mfb100_ics.hdf5" s=$($py -c "print(0.01 ** (1 / 3))") ;;
    *) echo "unknown run $run (SPH, MSPH, MFB, MFB100)" >&2; exit 2 ;;
  esac
  dir="$out/$run"
  mkdir -p "$dir"
  box=$($py -c "print(26.6 * $s)")
  soft=$($py -c "print(f'{0.012 * $scale * $s:.6g}')")
  soft_max=$($py -c "print(f'{0.006 * $scale * $s:.6g}')")
  # Gas exists only in the high-resolution region: its edge particles need h past their
  # half-empty surroundings, five of the finest spacings at most.
  h_max=$($py -c "print(f'{5 * 26.6 / 2 ** $lmax * $s:.6g}')")
  cat > "$dir/params.yml" <<EOT
initial_conditions: {file: $ics, periodic: true}
cosmology: {enabled: true, omega_m: 0.3, omega_lambda: 0.7, omega_b: 0.03, hubble_param: 0.6, a_end: 1}
gravity: {enabled: true, softening_dark_matter: $soft, softening_gas: $($py -c "print($soft / 2)"), softening_max_physical: $soft_max, mesh_cells: $mesh}
hydro: {msph: $msph, h_max: $h_max}
cooling: {enabled: true}
star_formation: {enabled: true}
feedback: {eps_cold: $eps, eps_hot: $eps}
time_integration: {$steps}
output: {directory: $dir, scale_factors: [$outputs], statistics_every: 50}
restart: {every_minutes: 10}
EOT
  if [ ! -f "$dir/done" ]; then
    echo "== $run (levels $levels, $mode settings, box $box Mpc/h)"
    started=$(date +%s)
    if [ -f "$dir/restart.hdf5" ]; then "$bin" run "$dir/params.yml" -q --restart "$@"
    else "$bin" run "$dir/params.yml" -q --overwrite "$@"; fi
    echo $(($(date +%s) - started)) >> "$dir/wall_seconds"
    touch "$dir/done"
  fi
  for snap in "$dir"/snapshot_*.hdf5; do
    hop="$dir/hop_$(basename "$snap" | sed 's/snapshot_//')"
    [ -f "$hop" ] || "$bin" hop "$snap" -o "$hop" "$@" 2>> "$dir/hop.log"
  done
done
$py "$here/plot_cosmological_galaxy.py" "$out"
