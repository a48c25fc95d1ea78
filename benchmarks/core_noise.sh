#!/bin/sh
# The host's noise floor for layouts that split a step's work between cores: two independent
# one-thread runs of the same Sedov problem at the same time, each bound to a core of its own,
# write their step logs; benchmarks/core_noise.py sets their full steps side by side. The same
# work on two cores should take the same time step by step; how far it does not is what a
# 2 x 1 run pays at every step's end and a 1 x 2 run evens out. JSON in
# benchmarks/results/core_noise.json. SEDOV_T_END (0.05) and CORES ("0 1") may be set.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
out="$root/benchmarks/results"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"
set -- ${CORES:-0 1}
bench="$root/build/benchmarks/fountain_run_bench"
taskset -c "$1" "$bench" sedov --threads 1 --t-end "${SEDOV_T_END:-0.05}" --step-log "$tmp/a.csv" > /dev/null &
pid=$!
taskset -c "$2" "$bench" sedov --threads 1 --t-end "${SEDOV_T_END:-0.05}" --step-log "$tmp/b.csv" > /dev/null
wait "$pid"
"${PYTHON:-/usr/bin/python3}" "$root/benchmarks/core_noise.py" "$tmp/a.csv" "$tmp/b.csv" \
  --label "two one-thread Sedov runs at once, on cores $1 and $2" --json "$out/core_noise.json"
