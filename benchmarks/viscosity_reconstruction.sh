#!/bin/sh
# The paper's viscosity against the reconstructed one (hydro.viscosity_reconstruction) on the
# same initial conditions, 2 threads, each run to its end: Sod (147,456 particles), Sedov
# (250,000), the Gresho vortex of docs/validation.md (13,824 particles, 32 neighbours, t = 1)
# and the 2 x 32^3 cosmological box (z = 49 to 0). Writes
# benchmarks/results/viscosity_<problem>_<paper|reconstructed>.json and prints steps, wall time
# and accuracy per run.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bench="$root/build/benchmarks"
out="$root/benchmarks/results"
mkdir -p "$out"
threads=${THREADS:-2}
for problem in sod sedov gresho box; do
  for viscosity in paper reconstructed; do
    flag=""
    [ "$viscosity" = reconstructed ] && flag="--viscosity-reconstruction"
    if [ "$problem" = box ]; then
      "$bench/fountain_cosmo_bench" -n 32 --box 32 --threads "$threads" $flag \
        --json "$out/viscosity_${problem}_${viscosity}.json" > /dev/null 2>&1
    elif [ "$problem" = gresho ]; then
      "$bench/fountain_run_bench" gresho -n 24 --neighbours 32 --threads "$threads" $flag \
        --json "$out/viscosity_${problem}_${viscosity}.json" > /dev/null
    else
      "$bench/fountain_run_bench" "$problem" --threads "$threads" $flag \
        --json "$out/viscosity_${problem}_${viscosity}.json" > /dev/null
    fi
  done
done
/usr/bin/python3 - "$out" <<'PY'
import json, sys
print("| problem | viscosity | steps | wall (s) | hydro task time (s) | accuracy |")
print("|---|---|---|---|---|---|")
for problem in ("sod", "sedov", "gresho", "box"):
    for viscosity in ("paper", "reconstructed"):
        r = json.load(open(f"{sys.argv[1]}/viscosity_{problem}_{viscosity}.json"))
        if problem == "sod":
            acc = f"density L1 {r['sod_density_l1']:.4f}"
        elif problem == "sedov":
            acc = f"shock radius {r['shock_radius']:.4f} (exact {r['shock_radius_exact']:.4f})"
        elif problem == "gresho":
            acc = f"v_phi L1 {r['gresho_velocity_l1']:.4f}"
        else:
            acc = ""
        hydro = f"{r['task_seconds']['hydro']:.1f}" if "task_seconds" in r else ""
        print(f"| {problem} | {viscosity} | {r['steps']} | {r['wall_s']:.1f} | {hydro} | {acc} |")
PY
