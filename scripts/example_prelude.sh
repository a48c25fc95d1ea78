# Sourced by the examples' run.sh after `set -eu`: sets here (the example's folder), root (the
# repository) and bin (the fountain binary, built if missing), and enters here/output.
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="$root/build/fountain"
[ -x "$bin" ] || sh "$root/scripts/build.sh"
mkdir -p "$here/output"
cd "$here/output"
