#!/bin/sh
# The convergence study of Marri & White (2003) section 3.2 (their Figs 1-3): the rotating
# collapsing sphere (M = 1e12 Msun/h, R = 100 kpc/h, 90% dark matter, spin 0.1) with cooling
# and no star formation, in standard SPH and MSPH, at 2000, 4000 and 8000 particles per
# species with dark-matter softenings of 2, 1.5 and 1 kpc/h (gas: half), to t = 1.2 Gyr.
#
#   sh examples/rotating_sphere/run_convergence.sh            # all six runs, then the plots
#   SIZES="2000" SCHEMES="msph" THREADS=1 sh examples/rotating_sphere/run_convergence.sh
#   JOBS=2 THREADS=1 sh examples/rotating_sphere/run_convergence.sh   # two runs at a time
#   MODE=fountain JOBS=2 THREADS=1 sh examples/rotating_sphere/run_convergence.sh   # Fountain's settings
#
# With JOBS > 1, that many runs go at once (largest first, each taking the next run left when
# it finishes; the last run goes on with all the workers' threads once the others are idle):
# on 2 cores, two 1-thread runs side by side finish the study sooner than one 2-thread run
# after another, as a single run's second thread idles in its serial parts.
# MODE: paper (the default: the paper's settings, no timestep limiter, dt_min 1e-8, a floor of
# h) or fountain (Fountain's defaults); run_or_resume.sh says which values. Runs go to
# examples/rotating_sphere/output/<N>_<scheme>/ (MODE=fountain: output/fountain/<N>_<scheme>/;
# $OUTPUT/<N>_<scheme>/ if set) and the figures to docs/validation/ (MODE=fountain:
# docs/validation/fountain/; $DOCS if set); a finished run is not redone.
# Internal units are the paper's (Mpc/h, Msun/h, km/s) with h = 1 for the cooling rates;
# the time unit is 977.8 Gyr, so 1.2 Gyr is t = 1.227e-3.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
. "$here/run_or_resume.sh"
root=$(cd "$here/../.." && pwd)
# FOUNTAIN_BIN: the executable (default build/fountain, built if missing).
bin=${FOUNTAIN_BIN:-$root/build/fountain}
[ -x "$bin" ] || sh "$root/scripts/build.sh"
set_mode
out=${OUTPUT:-$out_root}
if [ "$mode" = paper ]; then docs=${DOCS:-$root/docs/validation}; else docs=${DOCS:-$root/docs/validation/fountain}; fi
mkdir -p "$out"
threads=${THREADS:-2}
jobs=${JOBS:-1}
runs=""
for n in ${SIZES:-2000 4000 8000}; do
  case $n in
    2000) eps=0.002 ;;
    4000) eps=0.0015 ;;
    8000) eps=0.001 ;;
    *) eps=${SOFTENING:?set SOFTENING (Mpc/h) for N = $n} ;;
  esac
  ic="$out/sphere_$n.hdf5"
  make_sphere_ic "$ic" -n "$n"
  for scheme in ${SCHEMES:-sph msph}; do
    dir="$out/${n}_$scheme"
    runs="$runs ${n}_$scheme"
    [ -f "$dir/done" ] && continue
    mkdir -p "$dir"
    msph=false
    [ "$scheme" = msph ] && msph=true
    cat > "$dir/params.yml" <<EOT
# Rotating sphere, $n particles per species, $scheme, cooling on, star formation off ($mode settings).
run:
  t_end: 1.227e-3
initial_conditions:
  file: $ic
output:
  directory: $dir
  delta_time: 1.227e-4
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
EOT
  done
done

# A worker takes runs in turn, claiming each by creating its claim directory (atomic), so that
# workers never share a run; claims are cleared when the script starts. A worker that finds
# no run left marks itself idle; the last but one to do so stops the one run still going
# (SIGTERM: it writes a restart file) and that run's worker resumes it on every worker's
# threads, so no core idles beside the study's last run.
claims="$out/.claims"
rm -rf "$claims"
mkdir -p "$claims"
wide_threads=$((threads * jobs))
work() {
  for run in $1; do
    [ -f "$out/$run/done" ] && continue
    mkdir "$claims/$run" 2> /dev/null || continue
    echo "== $run (${threads} threads)"
    pid_file="$claims/$run/pid" widen_dir="$claims/$run/widen"
    run_or_resume "$out/$run"
  done
  [ "$jobs" -gt 1 ] || return 0
  mkdir "$claims/.idle_$2"
  [ "$(ls -d "$claims"/.idle_* | wc -l)" -eq $((jobs - 1)) ] || return 0
  for run in $1; do
    [ ! -f "$out/$run/done" ] && [ -f "$claims/$run/pid" ] || continue
    mkdir "$claims/$run/widen" 2> /dev/null || continue
    echo "== $run: the other workers are idle; restarting it on $wide_threads threads"
    kill -TERM "$(cat "$claims/$run/pid")" 2> /dev/null || true
  done
}
if [ "$jobs" -le 1 ]; then
  work "$runs" 0
else
  # Largest first: the runs' order reversed.
  reversed=""
  for run in $runs; do reversed="$run $reversed"; done
  pids=""
  k=0
  while [ "$k" -lt "$jobs" ]; do
    work "$reversed" "$k" &
    pids="$pids $!"
    k=$((k + 1))
  done
  failed=0
  for pid in $pids; do wait "$pid" || failed=$?; done
  [ "$failed" -eq 0 ] || exit "$failed"
fi
mkdir -p "$docs"
/usr/bin/python3 "$here/plot_convergence.py" "$out" --docs "$docs"
