#!/bin/sh
# The feedback experiments of Marri & White (2003) section 3.3 (their Figs 4 and 5): the
# rotating sphere with cooling and star formation, 4000 particles per species, DM softening
# 1.5 kpc/h (gas: half).
#   R01-R05: M = 1e12 Msun/h, (eps_c, eps_h, scheme) = (0, 0, SPH), (0, 0, MSPH),
#            (0, 0.8, MSPH), (0.4, 0.4, MSPH), (0.8, 0, MSPH).
#   G09-G12: eps_c = eps_h = 0.4, MSPH, M = 1e9 .. 1e12 Msun/h, radius and softening scaled
#            as M^(1/3) (G12 is R04).
#
#   sh examples/rotating_sphere/run_feedback.sh                     # all, then the plots
#   RUNS="R02 R04" N=2000 T_END=0.6 sh examples/rotating_sphere/run_feedback.sh
#   MODE=fountain sh examples/rotating_sphere/run_feedback.sh       # Fountain's settings
#
# N: particles per species (default 4000; the softening is scaled as N^(-1/3) from 1.5 kpc/h
# at 4000). T_END: Gyr (default 2, h = 1). THREADS: default 2. Runs go to
# $OUT/<run>/ (default examples/rotating_sphere/output/feedback_<N>, with MODE=fountain
# output/fountain/feedback_<N>); a finished run is not redone (delete its folder to redo it), a
# killed one continues from its restart file. MODE: paper (the default) or fountain
# (run_or_resume.sh). Scripts may run side by side on different RUNS of one OUT.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
. "$here/run_or_resume.sh"
root=$(cd "$here/../.." && pwd)
# FOUNTAIN_BIN: the executable (default build/fountain, built if missing); point it at a copy
# to keep rebuilding the tree while a long set runs.
bin=${FOUNTAIN_BIN:-$root/build/fountain}
[ -x "$bin" ] || sh "$root/scripts/build.sh"
n=${N:-4000}
t_end_gyr=${T_END:-2}
threads=${THREADS:-2}
set_mode
out=${OUT:-$out_root/feedback_$n}
mkdir -p "$out"
py=/usr/bin/python3
# Internal time unit: Mpc/(km/s) = 977.8 Gyr (h = 1).
t_end=$($py -c "print(f'{$t_end_gyr / 977.8:.6e}')")
dt_out=$($py -c "print(f'{$t_end_gyr / 977.8 / 10:.6e}')")

# G12 is R04 (the default list runs it once, as R04, and plots it in both figures).
for run in ${RUNS:-R01 R02 R03 R04 R05 G09 G10 G11}; do
  mass=1e12 msph=true eps_c=0.4 eps_h=0.4
  case $run in
    R01) eps_c=0 eps_h=0 msph=false ;;
    R02) eps_c=0 eps_h=0 ;;
    R03) eps_c=0 eps_h=0.8 ;;
    R04) ;;
    R05) eps_c=0.8 eps_h=0 ;;
    G09) mass=1e9 ;;
    G10) mass=1e10 ;;
    G11) mass=1e11 ;;
    G12) ;;
    *) echo "unknown run $run (R01-R05, G09-G12)" >&2; exit 2 ;;
  esac
  scale=$($py -c "print(($mass / 1e12) ** (1 / 3))")
  radius=$($py -c "print(0.1 * $scale)")
  eps=$($py -c "print(f'{0.0015 * $scale * (4000 / $n) ** (1 / 3):.6g}')")
  ic="$out/sphere_${mass}.hdf5"
  make_sphere_ic "$ic" -n "$n" --mass "$mass" --radius "$radius"
  dir="$out/$run"
  [ -f "$dir/done" ] && continue
  mkdir -p "$dir"
  cat > "$dir/params.yml" <<EOT
# $run: rotating sphere, M = $mass Msun/h, $n particles per species, eps_c = $eps_c, eps_h = $eps_h ($mode settings).
run:
  t_end: $t_end
initial_conditions:
  file: $ic
output:
  directory: $dir
  delta_time: $dt_out
  statistics_every: 20
restart:
  every_minutes: 10
time_integration:
  dt_max: 1.0e-6
  dt_min: $dt_min
  timestep_limiter: $limiter
hydro:
  msph: $msph
  h_min_ratio: $h_min_ratio
gravity:
  enabled: true
  softening_dark_matter: $eps
cooling:
  enabled: true
star_formation:
  enabled: true
feedback:
  eps_cold: $eps_c
  eps_hot: $eps_h
EOT
  echo "== $run ($n per species, M = $mass, eps_c = $eps_c, eps_h = $eps_h, MSPH $msph)"
  run_or_resume "$dir"
done

# PLOTS=0: runs only (scripts running side by side leave the figures to one last call).
[ "${PLOTS:-1}" = 1 ] || exit 0
plot() {  # plot NAME [--warm-and-hot] RUN...
  name=$1; shift
  extra=""
  [ "${1:-}" = --warm-and-hot ] && extra=$1 && shift
  dirs="" labels=""
  for r in "$@"; do
    [ -f "$out/$r/statistics.txt" ] && dirs="$dirs $out/$r" && labels="$labels $r"
  done
  [ -n "$dirs" ] || return 0
  # shellcheck disable=SC2086
  $py "$here/plot_star_formation.py" $dirs --labels $labels -o "$out/$name.png" --table "$out/$name.md" \
    --title "$name, $n particles per species" --at "$t_end_gyr" $extra
}
plot feedback_R R01 R02 R03 R04 R05
# G12 joins the mass sequence only beside another of its runs: R04 alone is no sequence.
if [ -f "$out/R04/statistics.txt" ] && [ ! -e "$out/G12" ] &&
  { [ -f "$out/G09/statistics.txt" ] || [ -f "$out/G10/statistics.txt" ] || [ -f "$out/G11/statistics.txt" ]; }; then
  ln -s R04 "$out/G12"
fi
# Fig 5 sums warm and hot gas, as the paper does for its mass sequence.
[ -e "$out/G12" ] && plot feedback_G --warm-and-hot G09 G10 G11 G12
$py "$here/compare_feedback.py" "$out" "$t_end_gyr" | tee "$out/comparison.md"
