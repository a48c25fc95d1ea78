#!/bin/sh
# Every script that draws a validation figure writes it through scripts/figure_stamp.py, and a
# figure so written carries the commit in its PNG Source field (FOUNTAIN_COMMIT overriding
# git's). Usage: test_figure_stamp.sh REPO_ROOT
set -eu
root=${1:?repo root}
python=${PYTHON:-/usr/bin/python3}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fountain_stamp.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM
fail() { echo "FAIL: $*"; exit 1; }

for f in "$root"/examples/*/plot_*.py "$root/scripts/plot_statistics.py"; do
  grep -q "savefig(" "$f" && fail "$f writes a figure without figure_stamp.save"
  grep -q "from figure_stamp import save" "$f" || fail "$f does not use figure_stamp.save"
done

stamp_of() {  # stamp_of PNG: its Source text field
  "$python" -c "import sys; from PIL import Image; print(Image.open(sys.argv[1]).text.get('Source', ''))" "$1"
}
draw='import sys, matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
sys.path.insert(0, sys.argv[1] + "/scripts"); from figure_stamp import save
fig, ax = plt.subplots(); ax.plot([0, 1]); save(fig, sys.argv[2])'
FOUNTAIN_COMMIT=abc123 "$python" -c "$draw" "$root" "$tmp/a.png"
[ "$(stamp_of "$tmp/a.png")" = "Fountain abc123" ] || fail "FOUNTAIN_COMMIT not stamped: '$(stamp_of "$tmp/a.png")'"
if git -C "$root" rev-parse --git-dir > /dev/null 2>&1; then
  want="Fountain $(git -C "$root" describe --always --dirty --abbrev=12)"
  "$python" -c "$draw" "$root" "$tmp/b.png"
  [ "$(stamp_of "$tmp/b.png")" = "$want" ] || fail "stamp '$(stamp_of "$tmp/b.png")', git says '$want'"
fi
echo "PASS: figures carry their commit"
