#!/bin/sh
# Checks tasks/plot_tasks.py on a tiny hand-written timeline: it draws a PNG, its summary names
# every task type, --summary-only draws nothing, and an empty timeline is not an error.
# Usage: test_plot_tasks.sh REPO_ROOT
set -eu

root=${1:?usage: test_plot_tasks.sh REPO_ROOT}
tool="$root/tasks/plot_tasks.py"
python=${PYTHON:-/usr/bin/python3}
[ -f "$tool" ] || { echo "FAIL: no $tool"; exit 1; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/fountain_plot_tasks.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM

fail() {
  echo "FAIL: $*"
  exit 1
}

cat > "$tmp/timeline_rank0.csv" <<'EOF'
# fountain task timeline: step=3 rank=0
type,subtype,category,ci,cj,rank,thread,start_ns,end_ns
density,self,hydro,0,-1,0,0,0,400000
density,self,hydro,1,-1,0,1,0,300000
density,pair,hydro,0,1,0,0,400000,1000000
kick,,integration,0,-1,0,0,1000000,1200000
kick,,integration,1,-1,0,1,1000000,1100000
EOF
cat > "$tmp/timeline_rank1.csv" <<'EOF'
# fountain task timeline: step=3 rank=1
type,subtype,category,ci,cj,rank,thread,start_ns,end_ns
density,self,hydro,2,-1,1,0,100000,500000
drift,,integration,2,-1,1,0,500000,600000
exchange,after_graph,mpi,-1,-1,1,-1,600000,900000
EOF

# Gantt chart plus summary.
"$python" "$tool" "$tmp/timeline_rank0.csv" "$tmp/timeline_rank1.csv" -o "$tmp/gantt.png" > "$tmp/out.txt" 2>&1 ||
  { cat "$tmp/out.txt"; fail "plot_tasks.py failed"; }
cat "$tmp/out.txt"
[ -s "$tmp/gantt.png" ] || fail "no PNG written"
head -c 8 "$tmp/gantt.png" | grep -q PNG || fail "gantt.png is not a PNG"
for t in density_self density_pair kick drift; do
  grep -q "^$t " "$tmp/out.txt" || fail "summary does not list task type $t"
done
# density_self: 0.4 + 0.3 + 0.4 ms over 3 tasks.
grep -Eq '^density_self +1\.100 +[0-9.]+% +3$' "$tmp/out.txt" || fail "wrong density_self line"
# rank 0 thread 1 is busy 0.4 ms of the 1.2 ms span: 66.7% idle.
grep -Eq '^ +0 +1 +0\.400 +66\.7% +2$' "$tmp/out.txt" || fail "wrong idle fraction for rank 0 thread 1"
# rank 1's exchanges after its graph (thread -1): 0.3 ms of the 1.2 ms span.
grep -Eq '^ +1 +- +0\.300 +25\.0% of the span in exchanges' "$tmp/out.txt" || fail "wrong exchange line for rank 1"

# --summary-only: the same summary, no picture.
"$python" "$tool" "$tmp/timeline_rank0.csv" --summary-only -o "$tmp/none.png" > "$tmp/out2.txt" 2>&1 ||
  { cat "$tmp/out2.txt"; fail "--summary-only failed"; }
[ ! -e "$tmp/none.png" ] || fail "--summary-only wrote a PNG"
grep -q "^kick " "$tmp/out2.txt" || fail "--summary-only printed no summary"

# An empty timeline (header only) is reported, not an error.
printf '# fountain task timeline: step=0 rank=0\ntype,subtype,category,ci,cj,rank,thread,start_ns,end_ns\n' \
  > "$tmp/empty.csv"
"$python" "$tool" "$tmp/empty.csv" -o "$tmp/empty.png" > "$tmp/out3.txt" 2>&1 ||
  { cat "$tmp/out3.txt"; fail "empty timeline gave an error"; }
grep -qi "no tasks" "$tmp/out3.txt" || fail "no message for an empty timeline"

echo "PASS: plot_tasks.py"
