#!/bin/sh
# compare_feedback.py prints the paper's claims only for runs that were made: with R04 alone
# (the demo) it says there is nothing to compare instead of an empty table; with R02 beside
# it, the R04-against-R02 row is filled. Usage: test_feedback_comparison.sh REPO_ROOT
set -eu
root=${1:?repo root}
python=${PYTHON:-/usr/bin/python3}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fountain_compare.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM
fail() { echo "FAIL: $*"; exit 1; }

stats() {  # stats RUN STELLAR_MASS: a two-line statistics file ending at 1 Gyr
  mkdir -p "$tmp/$1"
  cat > "$tmp/$1/statistics.txt" <<EOT
# time mass_gas mass_stars mass_stars_hidden mass_hot mass_warm mass_cold mass_unbound mass_promoted_diffuse
0 1.0 0 0 0.5 0.5 0 0 0
0.0010227 0.8 $2 0 0.3 0.2 0.3 0.01 0.02
EOT
}
stats R04 0.16
"$python" "$root/examples/rotating_sphere/compare_feedback.py" "$tmp" > alone.txt 2>&1 || { cat alone.txt; fail "R04 alone"; }
cat alone.txt
grep -q "nothing to compare" alone.txt || fail "R04 alone: no word that nothing compares"
! grep -q "^| the paper" alone.txt || fail "R04 alone: a table was printed"
stats R02 0.2
"$python" "$root/examples/rotating_sphere/compare_feedback.py" "$tmp" > both.txt 2>&1 || { cat both.txt; fail "R02 and R04"; }
cat both.txt
grep -q "^| R04 cuts star formation ~20% below R02 | 17% less stellar mass | yes |" both.txt || fail "no R04 row"
[ "$(grep -c '^| ' both.txt)" -eq 2 ] || fail "rows for runs that were not made"
echo "PASS"
