#!/bin/sh
# Installs what is missing, builds, and runs the demo: a 3D Sedov-Taylor blast, ending with
# a PNG of density against radius over the analytic solution (examples/sedov/output/).
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
sh "$root/scripts/install_deps.sh"
sh "$root/scripts/build.sh"
sh "$root/examples/sedov/run.sh"
