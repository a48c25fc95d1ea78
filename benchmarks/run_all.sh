#!/bin/sh
# Runs the standard benchmarks (SWIFT's SodShock_BCC_3D set-up and the 250k Sedov blast, each on
# 1 and 2 threads, N_ngb = 48) and writes one JSON file per run into benchmarks/results/.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/build/benchmarks/fountain_run_bench"
out="$root/benchmarks/results"
mkdir -p "$out"
for problem in ${PROBLEMS:-sod sedov}; do
  for t in 1 2; do
    "$bin" "$problem" --threads "$t" --json "$out/${problem}_t$t.json"
  done
done
"$root/build/benchmarks/fountain_bench_kernels" --benchmark_format=json > "$out/kernels.json"
