# Sourced by the end-to-end test scripts, which are called as SCRIPT FOUNTAIN_BINARY REPO_ROOT
# CASE: sets bin, root, case_name and python, moves into a fresh temporary folder that is
# removed on exit, and defines fail.
set -eu
bin=${1:?binary}
root=${2:?repo root}
case_name=${3:?case}
python=${PYTHON:-/usr/bin/python3}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fountain_test.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM
cd "$tmp"

fail() { echo "FAIL: $*"; exit 1; }
