#!/bin/sh
# Parallel efficiency on 2 threads of the collapsed rotating sphere (where the convergence
# study spends its time), measured as PAIRS alternated pairs of 1- and 2-thread runs (the
# order flips from pair to pair, so a drift in the machine's speed falls on both), each run
# writing its JSON into $OUT; then the summary of benchmarks/efficiency_report.py.
#   sh benchmarks/efficiency_pairs.sh                     # 8 pairs, 3 Myr each
#   PAIRS=4 T_END=1e-6 sh benchmarks/efficiency_pairs.sh
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${BENCH_BIN:-$root/build/benchmarks/fountain_sphere_bench}
ic=${COLLAPSED_SNAPSHOT:-$root/examples/rotating_sphere/output/fountain/8000_msph/snapshot_0008.hdf5}
out=${OUT:-$root/benchmarks/results/efficiency}
pairs=${PAIRS:-8}
[ -f "$ic" ] || { echo "no $ic: run MODE=fountain SIZES=8000 sh examples/rotating_sphere/run_convergence.sh first" >&2; exit 1; }
mkdir -p "$out"
rm -f "$out"/pair_*.json
k=1
while [ "$k" -le "$pairs" ]; do
  order="1 2"
  [ $((k % 2)) -eq 0 ] && order="2 1"
  for t in $order; do
    "$bin" --ic "$ic" --threads "$t" --t-end "${T_END:-3e-6}" --json "$out/pair_${k}_t$t.json" > /dev/null 2>&1
  done
  k=$((k + 1))
done
/usr/bin/python3 "$root/benchmarks/efficiency_report.py" "$out"
