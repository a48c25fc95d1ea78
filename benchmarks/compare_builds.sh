#!/bin/sh
# Two builds side by side on the standard problems, for a change that should not alter speed:
# each problem runs on the first build, then the second, REPEATS times (alternating, so that
# drifts of the host's speed fall on both), and the wall times go to one JSON file.
# Usage: compare_builds.sh BEFORE_BENCH_DIR AFTER_BENCH_DIR OUT.json
#   (a *_BENCH_DIR holds fountain_run_bench and fountain_sphere_bench, e.g. build/benchmarks)
# REPEATS (2) and THREADS (2) may be set.
set -eu
before=${1:?before bench dir}
after=${2:?after bench dir}
out=${3:?output json}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
threads=${THREADS:-2}
runs=""
for r in $(seq 1 "${REPEATS:-2}"); do
  for build in before after; do
    dir=$before; [ "$build" = after ] && dir=$after
    for problem in sod sedov; do
      "$dir/fountain_run_bench" "$problem" --threads "$threads" --json "$tmp/$build.$problem.$r.json" > /dev/null
      runs="$runs $tmp/$build.$problem.$r.json"
    done
    "$dir/fountain_sphere_bench" -n 8000 --threads "$threads" --t-end 2e-5 --json "$tmp/$build.sphere.$r.json" > /dev/null
    runs="$runs $tmp/$build.sphere.$r.json"
  done
done
"${PYTHON:-/usr/bin/python3}" - "$out" $runs <<'PY'
import json, os, sys, statistics
out, files = sys.argv[1], sys.argv[2:]
rows = {}
for f in files:
    build, problem, _, _ = os.path.basename(f).split('.')
    d = json.load(open(f))
    rows.setdefault(problem, {}).setdefault(build, []).append({'wall_s': d['wall_s'], 'steps': d['steps']})
summary = {}
for problem, by in rows.items():
    b = [r['wall_s'] for r in by['before']]
    a = [r['wall_s'] for r in by['after']]
    # The fastest of several runs is the best estimate of the undisturbed cost (load only slows).
    summary[problem] = {'before_wall_s': b, 'after_wall_s': a, 'steps': by['after'][0]['steps'],
                        'after_over_before': statistics.median(a) / statistics.median(b),
                        'fastest_after_over_fastest_before': min(a) / min(b)}
    print(f"{problem:8s} before {' '.join(f'{x:7.2f}' for x in b)}  after {' '.join(f'{x:7.2f}' for x in a)}"
          f"  median ratio {summary[problem]['after_over_before']:.3f}"
          f"  fastest ratio {summary[problem]['fastest_after_over_fastest_before']:.3f}")
json.dump(summary, open(out, 'w'), indent=1)
PY
