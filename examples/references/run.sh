#!/bin/sh
# The exact answers the cosmological runs are checked against (docs/validation.md, "Comoving
# runs" and "Periodic gravity against Ewald summation"): the background (E, t, D, f, D2, f2 and
# the leapfrog's factors) for Einstein-de Sitter and flat LCDM against closed forms and
# independent quadrature, and Ewald's periodic field against its published values.
#   sh examples/references/run.sh   (a few seconds)
set -eu
. "$(dirname "$0")/../../scripts/example_prelude.sh"
"$bin" reference background --omega-m 1 --omega-lambda 0 --a-begin 0.01 -o eds.txt
"$bin" reference background --omega-m 0.3 --omega-lambda 0.7 --a-begin 0.01 -o lcdm.txt
"$bin" reference ewald -o ewald
/usr/bin/python3 "$here/plot_background.py" eds.txt lcdm.txt "$root/docs/validation/cosmology_background.png"
/usr/bin/python3 "$here/plot_ewald.py" ewald "$root/docs/validation/ewald_reference.png"
