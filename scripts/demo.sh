#!/bin/sh
# Installs what is missing, builds, and runs the demo: a small rotating-sphere galaxy (the
# paper's R04: MSPH, cooling, star formation and multiphase feedback, eps_c = eps_h = 0.4;
# 2000 particles per species) to 1 Gyr, ending with a PNG of the gas phases, stellar mass
# and star formation rate against time:
#   examples/rotating_sphere/output/demo/demo.png
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
sh "$root/scripts/install_deps.sh"
sh "$root/scripts/build.sh"
out="$root/examples/rotating_sphere/output/demo"
rm -rf "$out/R04" "$out/G12"
# Fountain's own settings (the timestep limiter on), not the paper's step bounds.
MODE=fountain RUNS=R04 N=2000 T_END=1 OUT="$out" sh "$root/examples/rotating_sphere/run_feedback.sh"

/usr/bin/python3 "$root/examples/rotating_sphere/plot_star_formation.py" "$out/R04" --labels "R04 (2000 per species)" \
  -o "$out/demo.png" --title "Fountain demo: rotating sphere with MSPH, cooling, star formation and MFB"
echo "demo done: $out/demo.png"
