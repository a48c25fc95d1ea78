#!/bin/sh
# Every example problem's final snapshot, on 1 thread, 2 threads and 2 MPI ranks, against the
# digest stored in tests/data/snapshot_checksums.txt: a change meant to move code without
# changing results (a refactoring) must leave every bit of every problem as it was. A change
# that alters results on purpose rewrites the stored digests with UPDATE=1 and says why in its
# commit. Digests hold for the Release build (`sh scripts/build.sh`); other optimisation
# levels round differently.
# The task graph each run builds at its start is compared too: its dependency CSV (type links
# and their counts, on 1 rank and on each of 2 ranks) against tests/data/task_graphs/, so that
# moving the code that builds the graph leaves every dependency as it was.
# Usage: snapshot_checksums.sh FOUNTAIN_BINARY REPO_ROOT CASE   (UPDATE=1: store the digest)
. "$(dirname "$0")/cli_prelude.sh"
store="$root/tests/data/snapshot_checksums.txt"

periodic=true t_end=0.02 dt_max=0.001 dt_min=1e-12 extra=""
case $case_name in
  sod) "$bin" ic sod -n 24 -o ic.hdf5 > /dev/null ;;
  sedov) "$bin" ic sedov -n 10 -o ic.hdf5 > /dev/null; t_end=0.01 ;;
  gresho) "$bin" ic gresho -n 16 -o ic.hdf5 > /dev/null; t_end=0.01 ;;
  evrard)
    "$bin" ic evrard -n 6 -o ic.hdf5 > /dev/null
    periodic=false t_end=0.05 extra="gravity:
  enabled: true
  softening_gas: 0.01
  G: 1" ;;
  sphere_feedback)
    "$bin" ic sphere -n 300 -o ic.hdf5 > /dev/null
    periodic=false t_end=6e-4 dt_max=1e-5 dt_min=1e-14 extra="hydro:
  msph: true
gravity:
  enabled: true
  softening_dark_matter: 0.002
cooling:
  enabled: true
star_formation:
  enabled: true
feedback:
  eps_cold: 0.4
  eps_hot: 0.4" ;;
  *) fail "unknown case $case_name" ;;
esac
params() {  # params OUT_DIR
  cat > "params_$1.yml" <<EOT
run:
  t_end: $t_end
initial_conditions:
  file: ic.hdf5
  periodic: $periodic
output:
  directory: $1
  dump_task_graph: true
time_integration:
  dt_max: $dt_max
  dt_min: $dt_min
$extra
EOT
}
params t1; "$bin" run params_t1.yml -q -t 1 > t1.txt 2>&1 || { cat t1.txt; fail "1 thread"; }
params t2; "$bin" run params_t2.yml -q -t 2 > t2.txt 2>&1 || { cat t2.txt; fail "2 threads"; }
params r2
ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np 2 "$bin" run params_r2.yml -q -t 1 > r2.txt 2>&1 ||
  { cat r2.txt; fail "2 ranks"; }
d1=$("$python" "$root/tests/snapshot_digest.py" t1/snapshot_0001.hdf5)
d2=$("$python" "$root/tests/snapshot_digest.py" t2/snapshot_0001.hdf5)
dr=$("$python" "$root/tests/snapshot_digest.py" r2/snapshot_0001.hdf5)
[ "$d1" = "$d2" ] || fail "1 and 2 threads differ"
[ "$d1" = "$dr" ] || fail "1 thread and 2 ranks differ"
graphs="$root/tests/data/task_graphs"
# The rows sorted, without the version line: a graph, not the order its types were registered in.
graph_rows() { grep -v '^#' "$1" | sort; }
graph_rows t1/dependency_graph_0.csv > g1.csv
graph_rows t2/dependency_graph_0.csv > g2.csv
cmp -s g1.csv g2.csv || fail "the task graphs of 1 and 2 threads differ"
graph_rows r2/dependency_graph_0.csv > g_r0.csv
graph_rows r2/dependency_graph_1.csv > g_r1.csv
if [ "${UPDATE:-0}" = 1 ]; then
  mkdir -p "$graphs"
  cp g1.csv "$graphs/${case_name}_1rank.csv"
  cp g_r0.csv "$graphs/${case_name}_2ranks_0.csv"
  cp g_r1.csv "$graphs/${case_name}_2ranks_1.csv"
fi
for pair in "g1.csv ${case_name}_1rank.csv" "g_r0.csv ${case_name}_2ranks_0.csv" "g_r1.csv ${case_name}_2ranks_1.csv"; do
  set -- $pair
  [ -f "$graphs/$2" ] || fail "no task graph stored as $graphs/$2 (UPDATE=1 stores it)"
  diff "$graphs/$2" "$1" || fail "$case_name: the task graph differs from tests/data/task_graphs/$2"
done
if [ "${UPDATE:-0}" = 1 ]; then
  grep -v "^$case_name " "$store" 2>/dev/null > new.txt || true
  echo "$case_name $d1" >> new.txt
  sort new.txt > "$store"
  echo "stored: $case_name $d1"
  exit 0
fi
stored=$(sed -n "s/^$case_name //p" "$store")
[ -n "$stored" ] || fail "no digest stored for $case_name (UPDATE=1 stores it)"
[ "$d1" = "$stored" ] || fail "$case_name: digest $d1, stored $stored: the results changed"
echo "PASS: $case_name $d1 on 1 and 2 threads and 2 ranks"
