#!/bin/sh
# Checks tasks/rank_balance.py on hand-written timelines of two ranks, one full step and one
# partial, whose busy times, imbalance, tail and per-type ratios are known; and that a folder
# without timelines is an error that names it.
# Usage: test_rank_balance.sh REPO_ROOT
set -eu

root=${1:?usage: test_rank_balance.sh REPO_ROOT}
tool="$root/tasks/rank_balance.py"
python=${PYTHON:-/usr/bin/python3}
[ -f "$tool" ] || { echo "FAIL: no $tool"; exit 1; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/fountain_rank_balance.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM

fail() {
  echo "FAIL: $*"
  exit 1
}

header='type,subtype,category,ci,cj,rank,thread,start_ns,end_ns'
# Step 1, full (three tasks per rank). Rank 0: busy 100 ms over a 100 ms span; rank 1: busy
# 80 ms, then 20 ms of exchanges (thread -1, not a task). Imbalance 100 - 90 = 10 ms, no tail.
# Density ran 20 ms against 30 ms (0.667), force 50 against 60 (0.833), drift 10 and 10.
printf '# fountain task timeline: step=1 rank=0\n%s\n%s\n%s\n%s\n' "$header" \
  'drift,,integration,0,-1,0,0,0,10000000' 'density,,hydro,0,-1,0,0,10000000,40000000' \
  'force,,hydro,0,-1,0,0,40000000,100000000' > "$tmp/timeline_step000001_rank0.csv"
printf '# fountain task timeline: step=1 rank=1\n%s\n%s\n%s\n%s\n%s\n' "$header" \
  'drift,,integration,1,-1,1,0,0,10000000' 'density,,hydro,1,-1,1,0,10000000,30000000' \
  'force,,hydro,1,-1,1,0,30000000,80000000' 'exchange,after_graph,mpi,-1,-1,1,-1,80000000,100000000' \
  > "$tmp/timeline_step000001_rank1.csv"
# Step 2, partial (three tasks in all). Rank 0: busy 6 ms over a 9 ms span; rank 1: busy 8 ms
# over 8 ms. Imbalance 8 - 7 = 1 ms; span 9 ms, 1 ms beyond the busier rank.
printf '# fountain task timeline: step=2 rank=0\n%s\n%s\n%s\n' "$header" \
  'force,,hydro,0,-1,0,0,0,5000000' 'kick,close,integration,0,-1,0,0,8000000,9000000' \
  > "$tmp/timeline_step000002_rank0.csv"
printf '# fountain task timeline: step=2 rank=1\n%s\n%s\n' "$header" \
  'force,,hydro,1,-1,1,0,2000000,10000000' > "$tmp/timeline_step000002_rank1.csv"

"$python" "$tool" "$tmp" > "$tmp/out.txt" 2>&1 || { cat "$tmp/out.txt"; fail "rank_balance.py failed"; }
cat "$tmp/out.txt"
expect() { grep -Fq "$1" "$tmp/out.txt" || fail "expected the line: $1"; }
expect 'full steps: 1'
expect '  busy per rank (s): 0.100, 0.080'
expect '  graph span (s): 0.100; imbalance (busiest minus mean): 0.010; tail beyond the busiest: 0.000'
expect '  steps in which each rank was the busiest: rank 0 1, rank 1 0'
expect 'partial steps: 1'
expect '  busy per rank (s): 0.006, 0.008'
expect '  graph span (s): 0.009; imbalance (busiest minus mean): 0.001; tail beyond the busiest: 0.001'
expect '  steps in which each rank was the busiest: rank 0 0, rank 1 1'
expect '  density: 0.667 (0.667) over 1 steps'
expect '  force: 0.833 (0.833) over 1 steps'
expect '  drift: 1.000 (1.000) over 1 steps'

# A folder without timelines: an error naming it.
mkdir "$tmp/empty"
if "$python" "$tool" "$tmp/empty" > "$tmp/err.txt" 2>&1; then fail "an empty folder was not an error"; fi
grep -q "$tmp/empty" "$tmp/err.txt" || fail "the error does not name the folder"

echo "PASS: rank_balance.py"
