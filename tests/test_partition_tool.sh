#!/bin/sh
# Checks benchmarks/compare_partitions.cpp on a small Sedov run: on one rank every method
# gives no imbalance and no ghost bytes; on two, each method's figures are there, finite, and
# the ranks exchange ghost bytes. Usage: test_partition_tool.sh TOOL FOUNTAIN
set -eu
tool=${1:?usage: test_partition_tool.sh TOOL FOUNTAIN}
bin=${2:?usage: test_partition_tool.sh TOOL FOUNTAIN}
python=${PYTHON:-/usr/bin/python3}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fountain_partition_tool.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM
fail() {
  echo "FAIL: $*"
  exit 1
}
cd "$tmp"
"$bin" ic sedov -n 16 -o sedov.hdf5 > /dev/null 2>&1 || fail "cannot write the Sedov ICs"
cat > params.yml <<EOT
run:
  t_end: 0.002
initial_conditions:
  file: sedov.hdf5
  periodic: true
output:
  directory: out
time_integration:
  dt_max: 5.0e-4
hydro:
  msph: false
space:
  cell_split_size: 16
EOT
"$tool" params.yml -t 1 --ranks 1,2 --json out.json > run.txt 2>&1 || { cat run.txt; fail "the tool failed"; }
"$python" - out.json <<'PY' || fail "wrong figures: $(cat out.json)"
import json, math, sys
d = json.load(open(sys.argv[1]))
rows = {(r['ranks'], r['method']): r for r in d['partitions']}
assert d['steps'] > 0 and d['leaves_last'] > 8, d
for method in ('curve', 'metis', 'metis_tight'):
    one, two = rows[(1, method)], rows[(2, method)]
    assert one['imbalance'] == 0 and one['ghost_bytes_per_step'] == 0, one
    assert math.isfinite(two['imbalance']) and 0 <= two['imbalance'] < 1, two
    assert two['ghost_bytes_per_step'] > 0, two
PY
echo "PASS: $(cat out.json)"
