#!/bin/sh
# Runs the standard benchmarks (SWIFT's SodShock_BCC_3D set-up and the 250k Sedov blast, each on
# 1 and 2 threads, N_ngb = 48) and writes one JSON file per run into benchmarks/results/.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/build/benchmarks/fountain_run_bench"
out="$root/benchmarks/results"
mkdir -p "$out"
for problem in $(echo "${PROBLEMS:-sod sedov}" | tr ' ' '\n' | grep -v sphere); do
  for t in 1 2; do
    "$bin" "$problem" --threads "$t" --json "$out/${problem}_t$t.json"
  done
done
# The paper's rotating sphere, 8000 particles per species, MSPH, cooling and gravity, for
# t = 2e-5 (20 Myr) from the start.
if [ -z "${PROBLEMS:-}" ] || echo "$PROBLEMS" | grep -q sphere; then
  for t in 1 2; do
    "$root/build/benchmarks/fountain_sphere_bench" -n 8000 --threads "$t" --t-end 2e-5 --json "$out/sphere_t$t.json"
  done
  # The collapsed sphere, where the study spends its time: 3e-6 (3 Myr, ~1000 steps) from the
  # 8000-per-species MSPH run's snapshot at 0.98 Gyr, when the convergence study has made it.
  collapsed=${COLLAPSED_SNAPSHOT:-$root/examples/rotating_sphere/output/fountain/8000_msph/snapshot_0008.hdf5}
  if [ -f "$collapsed" ]; then
    for t in 1 2; do
      "$root/build/benchmarks/fountain_sphere_bench" --ic "$collapsed" --threads "$t" --t-end 3e-6 \
        --json "$out/sphere_collapsed_t$t.json" 2>/dev/null
    done
  else
    echo "skipping the collapsed sphere: no $collapsed (run MODE=fountain SIZES=8000 sh examples/rotating_sphere/run_convergence.sh)"
  fi
fi
"$root/build/benchmarks/fountain_bench_kernels" --benchmark_format=json > "$out/kernels.json"
