#!/bin/sh
# Checks tasks/rank_balance.py on hand-written timelines of two ranks, one full step and one
# partial, whose busy times, imbalance, tail and per-type ratios are known; the comparison
# with a one-rank run's timelines (--reference), task by task; and that a folder without
# timelines, or a reference without the ranks' tasks, is an error that names it.
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

# --reference: the same run on one rank. Its step 1 took drift 10 / 10, density 20 / 20 and
# force 50 / 40 ms for cells 0 / 1; step 2 force 5 / 8 ms and kick_close 1 ms for cell 0.
# Rank 0 ran cell 0's tasks (density 30 against 20 ms: 1.50; force 65 against 55: 1.18),
# rank 1 cell 1's (density 1.00; force 58 against 48: 1.21). A match by type alone, not by
# cell, would give other sums.
mkdir "$tmp/ref"
printf '# fountain task timeline: step=1 rank=0\n%s\n%s\n%s\n%s\n%s\n%s\n%s\n' "$header" \
  'drift,,integration,0,-1,0,0,0,10000000' 'drift,,integration,1,-1,0,1,0,10000000' \
  'density,,hydro,0,-1,0,0,10000000,30000000' 'density,,hydro,1,-1,0,1,10000000,30000000' \
  'force,,hydro,0,-1,0,0,30000000,80000000' 'force,,hydro,1,-1,0,1,30000000,70000000' \
  > "$tmp/ref/timeline_step000001.csv"
printf '# fountain task timeline: step=2 rank=0\n%s\n%s\n%s\n%s\n' "$header" \
  'force,,hydro,0,-1,0,0,0,5000000' 'force,,hydro,1,-1,0,1,0,8000000' \
  'kick,close,integration,0,-1,0,0,5000000,6000000' > "$tmp/ref/timeline_step000002.csv"
"$python" "$tool" "$tmp" --reference "$tmp/ref" > "$tmp/out.txt" 2>&1 || { cat "$tmp/out.txt"; fail "--reference failed"; }
cat "$tmp/out.txt"
expect '  force: rank 0 0.065 / 0.055 (1.18); rank 1 0.058 / 0.048 (1.21)'
expect '  density: rank 0 0.030 / 0.020 (1.50); rank 1 0.020 / 0.020 (1.00)'
expect '  drift: rank 0 0.010 / 0.010 (1.00); rank 1 0.010 / 0.010 (1.00)'
expect '  kick_close: rank 0 0.001 / 0.001 (1.00); rank 1 -'
expect '  all: rank 0 0.106 / 0.086 (1.23); rank 1 0.088 / 0.078 (1.13)'
expect '  (9 tasks matched; 0 without a counterpart, such as sends and receives)'
# A reference with none of the ranks' tasks is an error that names it.
mkdir "$tmp/other"
printf '# fountain task timeline: step=1 rank=0\n%s\n%s\n' "$header" 'drift,,integration,7,-1,0,0,0,10' \
  > "$tmp/other/timeline_step000001.csv"
if "$python" "$tool" "$tmp" --reference "$tmp/other" > "$tmp/err.txt" 2>&1; then fail "an unmatched reference was not an error"; fi
grep -q "$tmp/other" "$tmp/err.txt" || fail "the error does not name the reference folder"

# A folder without timelines: an error naming it.
mkdir "$tmp/empty"
if "$python" "$tool" "$tmp/empty" > "$tmp/err.txt" 2>&1; then fail "an empty folder was not an error"; fi
grep -q "$tmp/empty" "$tmp/err.txt" || fail "the error does not name the folder"

echo "PASS: rank_balance.py"
