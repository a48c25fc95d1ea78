#!/bin/sh
# The two Courant criteria side by side on the same initial conditions: Sod (147,456
# particles) and Sedov (250,000), 2 threads, each run to its end. Writes
# benchmarks/results/courant_<problem>_<criterion>.json and prints steps, wall time and
# accuracy per run.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/build/benchmarks/fountain_run_bench"
out="$root/benchmarks/results"
mkdir -p "$out"
for problem in sod sedov; do
  for criterion in syw signal_velocity; do
    "$bin" "$problem" --threads "${THREADS:-2}" --courant-criterion "$criterion" \
      --json "$out/courant_${problem}_${criterion}.json" > /dev/null
  done
done
/usr/bin/python3 - "$out" <<'PY'
import json, sys
print("| problem | criterion | steps | wall (s) | accuracy |")
print("|---|---|---|---|---|")
for problem in ("sod", "sedov"):
    for criterion in ("syw", "signal_velocity"):
        r = json.load(open(f"{sys.argv[1]}/courant_{problem}_{criterion}.json"))
        acc = (f"density L1 {r['sod_density_l1']:.4f}" if problem == "sod" else
               f"shock radius {r['shock_radius']:.4f} (exact {r['shock_radius_exact']:.4f})")
        print(f"| {problem} | {criterion} | {r['steps']} | {r['wall_s']:.1f} | {acc} |")
PY
