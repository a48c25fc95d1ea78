#!/bin/sh
# Strong scaling across ranks and threads: the same problem at every ranks x threads layout
# the machine offers (1x1, 1x2, 2x1 on two cores), one JSON file per run in
# benchmarks/results/scaling_<problem>_<ranks>x<threads>.json, then the table
# (python3 benchmarks/scaling_report.py). Problems: the 250k-particle Sedov blast (the
# engine benchmark's, run to SEDOV_T_END) and the 8000-per-species rotating sphere with star
# formation and MFB feedback on (to SPHERE_T_END). The Sedov run goes to t = 0.05, the
# benchmark's end (840 steps); SEDOV_T_END=0.01 gives its first 356 steps, the span of the
# older tables in docs/performance.md. PIN=1 pins every task
# thread to a core (--pin, run.pin_threads).
# The host's own step-to-step difference between its cores goes with the table, since a 2 x 1
# run pays it and a 1 x 2 run does not: the Sedov 2 x 1 runs log their steps, and the last
# one's two ranks are set side by side (core_noise_2x1_ranks.json), then two independent
# one-thread runs are (benchmarks/core_noise.sh; core_noise.json). NOISE=0 leaves both out.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
out="$root/benchmarks/results"
mkdir -p "$out"
mpirun_n() { mpirun --allow-run-as-root --oversubscribe --bind-to none -np "$@"; }
layouts=${LAYOUTS:-"1x1 1x2 2x1"}
pin=""
if [ "${PIN:-0}" = 1 ]; then pin="--pin"; fi
rm -f "$out"/scaling_*.json
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
for repeat in $(seq "${REPEATS:-3}"); do
for layout in $layouts; do
  ranks=${layout%x*} threads=${layout#*x}
  if echo "${PROBLEMS:-sedov sphere}" | grep -q sedov; then
    mpirun_n "$ranks" "$root/build/benchmarks/fountain_run_bench" sedov --threads "$threads" $pin \
      --t-end "${SEDOV_T_END:-0.05}" --json "$out/scaling_sedov_${layout}_$repeat.json" \
      --step-log "$logs/sedov_$layout.csv" > /dev/null
  fi
  if echo "${PROBLEMS:-sedov sphere}" | grep -q sphere; then
    mpirun_n "$ranks" "$root/build/benchmarks/fountain_sphere_bench" -n 8000 --threads "$threads" $pin \
      --star-formation --eps-cold 0.4 --eps-hot 0.4 --t-end "${SPHERE_T_END:-2e-5}" \
      --json "$out/scaling_sphere_${layout}_$repeat.json" > /dev/null
  fi
done
done
if [ "${NOISE:-1}" != 0 ] && [ -f "$logs/sedov_2x1.csv.rank1" ]; then
  "${PYTHON:-/usr/bin/python3}" "$root/benchmarks/core_noise.py" "$logs/sedov_2x1.csv.rank0" "$logs/sedov_2x1.csv.rank1" \
    --label "the two ranks of the last Sedov 2 x 1 run" --json "$out/core_noise_2x1_ranks.json"
  SEDOV_T_END=${SEDOV_T_END:-0.05} sh "$root/benchmarks/core_noise.sh"
fi
"${PYTHON:-/usr/bin/python3}" "$root/benchmarks/scaling_report.py" "$out"
