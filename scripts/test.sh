#!/bin/sh
# Installs what is missing, builds, and runs every test. The README's test command.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
sh "$root/scripts/install_deps.sh"
sh "$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure -j 2 "$@"
