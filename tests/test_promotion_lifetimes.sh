#!/bin/sh
# promotion_lifetimes.py gives the mean time promoted gas stays out of the cold phase as the
# mean promoted-and-not-cold mass over the rate promotions add mass (Little's law): a run with
# 0.02 of its baryons promoted and not cold throughout and 1000 promotions per Gyr of
# particles of 1e-3 must give 20 Myr; a run without promotions has no lifetime; a statistics
# file without the promotions column is refused. Usage: test_promotion_lifetimes.sh REPO_ROOT
set -eu
root=${1:?repo root}
python=${PYTHON:-/usr/bin/python3}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fountain_lifetimes.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM
fail() { echo "FAIL: $*"; exit 1; }

run() {  # run NAME PROMOTIONS_PER_GYR [COLUMNS]: statistics at 0-1 Gyr and a first snapshot
  mkdir -p "$tmp/$1"
  "$python" - "$tmp/$1" "$2" "${3:-promotions}" <<'PY'
import sys, h5py, numpy as np
folder, per_gyr, last = sys.argv[1], float(sys.argv[2]), sys.argv[3]
with open(f"{folder}/statistics.txt", "w") as f:
    f.write(f"# time step mass_gas mass_stars mass_stars_hidden mass_promoted_diffuse {last}\n")
    for k, t in enumerate((0.0, 0.3, 0.5, 0.7, 1.0)):
        f.write(f"{t / 977.8:.10e} {k} 1.0 0 0 {0.02 if per_gyr > 0 else 0.0} {int(round(per_gyr * t))}\n")
with h5py.File(f"{folder}/snapshot_0000.hdf5", "w") as f:
    f["PartType0/InitialMasses"] = np.full(1000, 1e-3)
PY
}
run steady 1000
run none 0
run old 1000 h_min_gas
out=$("$python" "$root/examples/rotating_sphere/promotion_lifetimes.py" "$tmp/steady" "$tmp/none") || fail "$out"
echo "$out"
echo "$out" | grep -q "^| steady | 0.30-1.00 | 700 | 1.0 | 0.0200 | 20.00 | 1,000 |$" || fail "steady run: not 20 Myr"
echo "$out" | grep -q "^| none | 0.30-1.00 | 0 | 0.0 | 0.0000 | - (no promotion) | 0 |$" || fail "run without promotions"
if "$python" "$root/examples/rotating_sphere/promotion_lifetimes.py" "$tmp/old" > "$tmp/old.txt" 2>&1; then
  fail "a file without the promotions column was read"
fi
grep -q "no promotions column" "$tmp/old.txt" || { cat "$tmp/old.txt"; fail "no word of the missing column"; }
echo "PASS"
