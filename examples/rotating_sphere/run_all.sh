#!/bin/sh
# Every rotating-sphere figure of Marri & White (2003) in one go: the convergence study (Figs
# 1-3: SPH and MSPH at 2000, 4000 and 8000 particles per species, cooling only, to 1.2 Gyr) and
# the feedback runs (Figs 4-5: R01-R05 and G09-G11 at 4000 per species, G12 being R04, to
# T_END Gyr, default 1), then their figures and tables.
#
#   sh examples/rotating_sphere/run_all.sh                  # the paper's settings
#   MODE=fountain sh examples/rotating_sphere/run_all.sh    # Fountain's settings
#   MODE=both sh examples/rotating_sphere/run_all.sh        # the paper's, then Fountain's
#
# MODE, H_MIN_RATIO, FOUNTAIN_BIN: as for run_convergence.sh and run_feedback.sh (their
# folders, resuming and restart files too). The runs go JOBS at a time (default 2) on one
# thread each: on 2 cores that finishes sooner than one 2-thread run after another. The wall
# time of each part is appended to <output>/run_all_seconds.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
if [ "${MODE:-paper}" = both ]; then
  status=0
  MODE=paper sh "$0" || status=$?
  MODE=fountain sh "$0" || status=$?
  exit "$status"
fi
jobs=${JOBS:-2}
t_end=${T_END:-1.0}
export MODE="${MODE:-paper}"
. "$here/run_or_resume.sh"
set_mode
mkdir -p "$out_root"
log="$out_root/run_all_seconds"
started=$(date +%s)

JOBS=$jobs THREADS=1 sh "$here/run_convergence.sh"
echo "convergence $(($(date +%s) - started))" >> "$log"

# The feedback runs in two chains side by side (balanced by their measured lengths), then the
# figures and tables.
set -- "R01 R03 R05 G10" "R02 R04 G09 G11"
[ "$jobs" -gt 1 ] || set -- "R01 R02 R03 R04 R05 G09 G10 G11"
pids=""
for chain in "$@"; do
  # A run that stops does not stop its chain: the runs after it still go.
  (
    status=0
    for run in $chain; do
      PLOTS=0 RUNS="$run" N=4000 T_END="$t_end" THREADS=1 sh "$here/run_feedback.sh" || status=$?
    done
    exit "$status"
  ) > "$out_root/run_all_feedback_$$_${chain%% *}.log" 2>&1 &
  pids="$pids $!"
done
failed=0
for pid in $pids; do wait "$pid" || failed=$?; done
# The figures and tables of the runs that finished (a run that stopped, at dt_min say, is
# drawn as far as it went and left out of the paper's claims; its chain's log says why).
finished=""
for run in R01 R02 R03 R04 R05 G09 G10 G11; do
  [ -f "$out_root/feedback_4000/$run/done" ] && finished="$finished $run"
done
[ -z "$finished" ] || RUNS="$finished" N=4000 T_END="$t_end" THREADS=1 sh "$here/run_feedback.sh"
echo "feedback $(($(date +%s) - started))" >> "$log"
if [ "$failed" -ne 0 ]; then
  echo "a feedback run stopped (exit status $failed); see $out_root/run_all_feedback_$$_*.log" >&2
  exit "$failed"
fi
echo "all rotating-sphere figures done in $(($(date +%s) - started)) s ($MODE settings)"
