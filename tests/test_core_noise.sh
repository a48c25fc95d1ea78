#!/bin/sh
# Checks benchmarks/core_noise.py on hand-written step logs whose full steps, ratios and loss
# are known: partial and rebuilt steps are left out, the loss is sum(max) / sum(mean) - 1, and
# logs with fewer than two common full steps are an error that names them.
# Usage: test_core_noise.sh REPO_ROOT
set -eu

root=${1:?usage: test_core_noise.sh REPO_ROOT}
tool="$root/benchmarks/core_noise.py"
python=${PYTHON:-/usr/bin/python3}
[ -f "$tool" ] || { echo "FAIL: no $tool"; exit 1; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/fountain_core_noise.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM

fail() {
  echo "FAIL: $*"
  exit 1
}

header='step,active,rebuilt,step_wall_s,tasks_wall_s,tasks_busy_s'
# Full steps 2, 4 and 5 (100 particles, not rebuilt): A takes 0.3, 0.2, 0.1 s; B 0.2, 0.2, 0.3 s.
# Ratios 1.5, 1.0, 1/3 (mean 0.9444); max per step 0.3 + 0.2 + 0.3 = 0.8 against means
# 0.25 + 0.2 + 0.2 = 0.65: loss 0.8 / 0.65 - 1 = 0.2308. Step 1 is partial and step 3 rebuilt:
# their large differences must not count. The ratios' logs (0.4055, 0, -1.0986) correlate
# -0.044 from one full step to the next.
printf '%s\n' "$header" '1,10,0,1,1,5.0' '2,100,0,1,1,0.3' '3,100,1,1,1,9.0' '4,100,0,1,1,0.2' '5,100,0,1,1,0.1' > "$tmp/a.csv"
printf '%s\n' "$header" '1,10,0,1,1,0.1' '2,100,0,1,1,0.2' '3,100,1,1,1,0.1' '4,100,0,1,1,0.2' '5,100,0,1,1,0.3' > "$tmp/b.csv"
"$python" "$tool" "$tmp/a.csv" "$tmp/b.csv" --label test --json "$tmp/out.json" > "$tmp/out.txt" || fail "the tool failed"
"$python" - "$tmp/out.json" <<'PY' || fail "wrong figures: $(cat "$tmp/out.json")"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["full_steps"] == 3, d
assert d["label"] == "test", d
assert abs(d["step_ratio_mean"] - 0.9444) < 1e-4, d
assert abs(d["step_ratio_min"] - 0.3333) < 1e-4 and abs(d["step_ratio_max"] - 1.5) < 1e-4, d
assert abs(d["loss_waiting_for_slower_side"] - 0.2308) < 1e-4, d
assert abs(d["step_ratio_lag1_correlation"] - (-0.044)) < 1e-3, d
assert abs(d["task_s_a"] - 0.6) < 1e-9 and abs(d["task_s_b"] - 0.7) < 1e-9, d
PY
grep -q "23.1%" "$tmp/out.txt" || fail "the summary line lacks the loss: $(cat "$tmp/out.txt")"

# One common full step is too few: the error names the logs.
printf '%s\n' "$header" '2,100,0,1,1,0.3' > "$tmp/c.csv"
if "$python" "$tool" "$tmp/c.csv" "$tmp/b.csv" > "$tmp/err.txt" 2>&1; then fail "one full step was accepted"; fi
grep -q "c.csv" "$tmp/err.txt" || fail "the error does not name the log: $(cat "$tmp/err.txt")"
echo "core_noise.py: figures and errors as expected"
