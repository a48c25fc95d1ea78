#!/bin/sh
# End-to-end checks of what guards a user's files and time: the output folder's lock, the
# refusal to replace an earlier run's files, options and times the run cannot honour, and
# the messages that name the cause. Each case fails on a build without its guard.
# Usage: cli_guard_tests.sh FOUNTAIN_BINARY REPO_ROOT CASE
. "$(dirname "$0")/cli_prelude.sh"

# params IC_FILE OUT_DIR T_END [extra sections]; RUN_KEYS and OUTPUT_KEYS: more lines (indented)
# for the run and output sections.
params() {
  cat > params.yml <<EOT
run:
  t_end: $3
${RUN_KEYS:-}
initial_conditions:
  file: $1
  periodic: true
output:
  directory: $2
${OUTPUT_KEYS:-}
time_integration:
  dt_max: 0.001
  dt_min: 1e-12
${4:-}
EOT
}

# refused PATTERN COMMAND...: the command exits with status 2 and prints PATTERN.
refused() {
  pattern=$1; shift
  set +e
  "$@" > out.txt 2>&1
  status=$?
  set -e
  [ "$status" -eq 2 ] || { cat out.txt; fail "$*: exit status $status, expected 2"; }
  grep -q -- "$pattern" out.txt || { cat out.txt; fail "$*: the message does not mention '$pattern'"; }
  echo "ok ($*): $(head -c 300 out.txt)"
}

"$bin" ic sedov -n 8 -o good.hdf5 > /dev/null 2>&1 || fail "cannot write ICs"

case "$case_name" in
  output_times)
    # An output interval below one tick of the integer timeline would give steps of length 0
    # and a snapshot per step at one time: refused before any work, naming the key.
    OUTPUT_KEYS="  delta_time: 1e-300" params good.hdf5 out 0.001
    refused "params.yml:[0-9]*: key 'output.delta_time' = 1e-300 is shorter than one tick" "$bin" run params.yml -q
    [ ! -e out/snapshot_0000.hdf5 ] || fail "a snapshot was written before the refusal"
    # A valid interval: every snapshot at its own time, every step of positive length.
    sed -i 's/delta_time: 1e-300/delta_time: 0.0003/; s/t_end: 0.001/t_end: 0.0012/' params.yml
    "$bin" run params.yml > run.txt 2>&1 || { cat run.txt; fail "run"; }
    ! grep -q "dt = 0  " run.txt || { grep "dt = 0  " run.txt | head -3; fail "a step of length 0"; }
    "$python" -c "
import glob, h5py, sys
times = [h5py.File(f, 'r')['Header'].attrs['Time'] for f in sorted(glob.glob('out/snapshot_*.hdf5'))]
print('snapshot times', times)
sys.exit(0 if len(times) == 5 and all(a < b for a, b in zip(times, times[1:])) else 1)" || fail "snapshot times"
    # t_end far beyond dt_max's reach: the message names both keys.
    params good.hdf5 out2 1e15
    refused "time_integration.dt_max.*shorter than one tick.*run.t_end = 1e+15" "$bin" run params.yml -q ;;
  output_lock)
    # One run at a time in a folder: a second is refused naming the holder; a lock left by a
    # killed run is recognised and taken over.
    params good.hdf5 out 0.01
    sed -i 's/dt_max: 0.001/dt_max: 1e-5/' params.yml  # 1000 steps: long enough to be met
    "$bin" run params.yml -q > first.txt 2>&1 &
    pid=$!
    n=0
    until [ -s out/.fountain.lock ] || [ $n -ge 500 ]; do sleep 0.01; n=$((n + 1)); done
    kill -0 "$pid" 2>/dev/null || fail "the first run ended before the second could meet its lock"
    refused "output directory 'out' is in use by another run (PID $pid on host" "$bin" run params.yml -q --overwrite
    kill "$pid"; wait "$pid" 2>/dev/null || true
    # SIGTERM left a restart file; the lock of the stopped run is free again.
    "$bin" run params.yml -q --restart > resumed.txt 2>&1 || { cat resumed.txt; fail "restart after the first run"; }
    # A lock file whose holder is gone (a killed run leaves one behind).
    echo "PID 999999 on host elsewhere" > out/.fountain.lock
    "$bin" run params.yml --overwrite > stale.txt 2>&1 || { cat stale.txt; fail "run over a stale lock"; }
    grep -q "took over the lock of out left by a run that did not end (PID 999999 on host elsewhere)" stale.txt ||
      { cat stale.txt; fail "the stale lock was not reported"; }
    [ ! -e out/.fountain.lock ] || fail "the lock was left behind by a finished run" ;;
  earlier_outputs)
    # A fresh run does not replace an earlier run's files without --overwrite, and never
    # writes over its own inputs.
    T=0.003
    OUTPUT_KEYS="  delta_time: 0.001" params good.hdf5 out $T
    "$bin" run params.yml -q > /dev/null 2>&1 || fail "first run"
    cp out/snapshot_0003.hdf5 kept.hdf5
    refused "output directory 'out' holds an earlier run's files (snapshot_0000.hdf5, snapshot_0001.hdf5, snapshot_0002.hdf5 and 1 more)" \
      "$bin" run params.yml -q
    cmp -s out/snapshot_0003.hdf5 kept.hdf5 || fail "the refused run changed a snapshot"
    # A resumable run: the message says how to continue it.
    "$bin" ic sedov -n 8 -o good.hdf5 > /dev/null 2>&1
    touch out/restart.hdf5
    refused "pass --restart" "$bin" run params.yml -q
    rm out/restart.hdf5
    # --overwrite replaces them all: a shorter run leaves no snapshot of the earlier one.
    sed -i "s/t_end: $T/t_end: 0.001/" params.yml
    "$bin" run params.yml -q --overwrite > /dev/null 2>&1 || fail "run with --overwrite"
    [ "$(ls out/snapshot_*.hdf5 | wc -l)" -eq 2 ] || { ls out; fail "snapshots of the earlier run are left"; }
    # Its own initial conditions in its output folder, under a name it writes: refused, even
    # with --overwrite, and the file is untouched.
    cp good.hdf5 out/snapshot_0007.hdf5
    cp good.hdf5 ic_copy.hdf5
    sed -i 's|file: good.hdf5|file: out/snapshot_0007.hdf5|' params.yml
    refused "out/snapshot_0007.hdf5 is an input of this run" "$bin" run params.yml -q --overwrite
    cmp -s out/snapshot_0007.hdf5 ic_copy.hdf5 || fail "the initial conditions were changed" ;;
  ic_options)
    for n in 0 -5; do refused "option -n,--resolution = $n must be a positive" "$bin" ic sedov -n "$n" -o a.hdf5; done
    for g in 0 -1 1 nan; do refused "option --gamma = $g must be a finite adiabatic index" "$bin" ic sod --gamma "$g" -o a.hdf5; done
    refused "ic sedov -n 2000 would make about 1.6e+10 particles, needing about .* of memory" "$bin" ic sedov -n 2000 -o a.hdf5
    refused "option --spin applies to the sphere only" "$bin" ic sod --spin 0.1 -o a.hdf5
    [ ! -e a.hdf5 ] || fail "a refused request wrote a file" ;;
  space_and_h_limits)
    # More top cells than particles would stall the run: refused with the reason.
    params good.hdf5 out 0.001 "space:
  top_cells: 64"
    refused "params.yml:[0-9]*: key 'space.top_cells' = 64 makes 64 x 64 x 64 = 262144 top-level cells for 1024 particles" \
      "$bin" run params.yml -q
    # An h_max below the h the particles need: the run goes on, warning and counting.
    params good.hdf5 out2 0.001 "hydro:
  h_max: 0.05"
    "$bin" run params.yml -q > capped.txt 2>&1 || { cat capped.txt; fail "run with h_max"; }
    grep -q "warning: 1024 particles were held at hydro.h_max = 0.05" capped.txt || { cat capped.txt; fail "no warning"; }
    grep -q "particle-steps were held at hydro.h_max" capped.txt || { cat capped.txt; fail "no count at the end"; } ;;
  parameter_file_limits)
    refused "is larger than 16 MiB" "$bin" run /dev/zero -q
    head -c 17000000 /dev/zero | tr '\0' '#' > huge.yml
    refused "huge.yml: the parameter file is larger than 16 MiB" "$bin" run huge.yml -q
    mkdir folder
    refused "folder: is a folder, not a parameter file" "$bin" run folder -q ;;
  option_messages)
    # -t takes run.threads' range and message.
    params good.hdf5 out 0.001
    for t in -1 10000; do refused "key 'run.threads' = $t is out of range \[0, 4096\]" "$bin" run params.yml -t "$t"; done
    RUN_KEYS="  threads: 10000" params good.hdf5 out 0.001
    refused "params.yml:3: key 'run.threads' = 10000 is out of range \[0, 4096\]" "$bin" run params.yml
    params good.hdf5 out 0.001
    refused "option --abandon-after-steps = 0 must be a positive step count" "$bin" run params.yml --abandon-after-steps 0
    refused "unknown command 'frobnicate': expected one of run, ic, fof, hop, mass-function, reference, params" "$bin" frobnicate
    sed -i 's|file: good.hdf5|file: ""|' params.yml
    refused "params.yml:[0-9]*: key 'initial_conditions.file' is empty" "$bin" run params.yml
    params good.hdf5 out 0.001 "cooling:
  metallicity: -4"
    refused "params.yml:[0-9]*: key 'cooling.metallicity' = -4 is out of range \[-3, 0.5\]" "$bin" run params.yml ;;
  particle_layout)
    # Particles at one point, or a periodic box smaller than their extent: the cause is named
    # before the run, not left to a smoothing length that cannot converge.
    "$python" -c "
import h5py, shutil
for name in ('one', 'small'):
    shutil.copy('good.hdf5', name + '.hdf5')
with h5py.File('one.hdf5', 'a') as f: f['PartType0/Coordinates'][:] = 0.3
with h5py.File('small.hdf5', 'a') as f: f['Header'].attrs['BoxSize'] = 0.5"
    params one.hdf5 out 0.001
    refused "one.hdf5: gas particles ID [0-9]* and ID [0-9]* (and 1022 more) lie at the same position (0.3, 0.3, 0.3)" \
      "$bin" run params.yml -q
    params small.hdf5 out 0.001
    refused "small.hdf5: the particles span 0.9375 along x .* more than the periodic box's side /Header/BoxSize = 0.5" \
      "$bin" run params.yml -q ;;
  ic_time)
    # A snapshot used as initial conditions goes on from its time, unless run.t_begin says
    # otherwise (then a warning).
    "$python" -c "
import h5py, shutil
shutil.copy('good.hdf5', 'later.hdf5')
with h5py.File('later.hdf5', 'a') as f: f['Header'].attrs['Time'] = 0.5"
    params later.hdf5 out 0.502
    "$bin" run params.yml -q > run.txt 2>&1 || { cat run.txt; fail "run from t = 0.5"; }
    "$python" -c "
import h5py, sys
t0 = h5py.File('out/snapshot_0000.hdf5', 'r')['Header'].attrs['Time']
print('first snapshot at', t0)
sys.exit(0 if t0 == 0.5 else 1)" || fail "the run did not start at the initial conditions' time"
    RUN_KEYS="  t_begin: 0" params later.hdf5 out2 0.002
    "$bin" run params.yml -q > warned.txt 2>&1 || { cat warned.txt; fail "run with t_begin"; }
    grep -q "key 'run.t_begin' = 0 differs from /Header/Time = 0.5 of later.hdf5" warned.txt ||
      { cat warned.txt; fail "no warning"; } ;;
  restart_points)
    # The first restart file is written at the start, so a run killed before its first due
    # restart file goes on from there, bit for bit; after a restart from inside a step, the
    # step's log line gives the step's true start and length.
    extra="restart:
  every_steps: 4"
    OUTPUT_KEYS="  delta_time: 0.008" params good.hdf5 outA 0.03 "$extra"; cp params.yml paramsA.yml
    OUTPUT_KEYS="  delta_time: 0.008" params good.hdf5 outB 0.03 "$extra"; cp params.yml paramsB.yml
    "$bin" run paramsA.yml > runA.txt 2>&1 || { cat runA.txt; fail "uninterrupted run"; }
    "$bin" run paramsB.yml --abandon-after-steps 2 > runB.txt 2>&1 || { cat runB.txt; fail "run B"; }
    grep -q "restart file outB/restart.hdf5 at step 0" runB.txt || { cat runB.txt; fail "no restart file at the start"; }
    "$bin" run paramsB.yml --restart > restart.txt 2>&1 || { cat restart.txt; fail "restart from step 0"; }
    for f in outA/snapshot_*.hdf5; do "$python" "$root/tests/compare_snapshots.py" "$f" "outB/${f#outA/}"; done
    rm -rf outB
    "$bin" run paramsB.yml --abandon-after-steps 13 > runB.txt 2>&1 || { cat runB.txt; fail "run B"; }
    # The last restart file was written inside step 13, which ends at the first output time: a
    # kill after it and before that snapshot leaves no snapshot_0001, which the restarted run
    # must write.
    grep -q "restart file outB/restart.hdf5 at step 12" runB.txt || { cat runB.txt; fail "test set-up: restart points moved"; }
    grep "^step *13 " runB.txt | grep -q "t = 0.008 " || fail "test set-up: step 13 no longer ends at an output"
    rm outB/snapshot_0001.hdf5
    "$bin" run paramsB.yml --restart > restart.txt 2>&1 || { cat restart.txt; fail "restart"; }
    head -2 restart.txt
    # The same snapshots, each at its time: none passed over, none written twice.
    [ "$(ls outA)" = "$(ls outB)" ] || { ls outA outB; fail "the restarted run wrote other files"; }
    for f in outA/snapshot_*.hdf5; do "$python" "$root/tests/compare_snapshots.py" "$f" "outB/${f#outA/}"; done
    step=$(sed -n 's/^restarted from .* at t = \(.*\), step \([0-9]*\)$/\2/p' restart.txt)
    t_restart=$(sed -n 's/^restarted from .* at t = \(.*\), step \([0-9]*\)$/\1/p' restart.txt)
    [ -n "$step" ] || fail "no restart line"
    # The restart line's time is the end of the step before, as run A logged it.
    grep -q "^step *$step  t = $t_restart " runA.txt || { grep "^step *$step " runA.txt; fail "restart time $t_restart is not step $step's end"; }
    # The first step after it logs the same time and length as run A's.
    next=$((step + 1))
    lineA=$(grep "^step *$next " runA.txt | sed 's/wall = .*//; s/rebuilt//; s/  */ /g')
    lineR=$(grep "^step *$next " restart.txt | sed 's/wall = .*//; s/rebuilt//; s/  */ /g')
    [ "$lineA" = "$lineR" ] || fail "step $next after the restart: '$lineR', uninterrupted: '$lineA'"
    for f in outA/snapshot_*.hdf5; do "$python" "$root/tests/compare_snapshots.py" "$f" "outB/${f#outA/}"; done ;;
  every_ic_problem_opens_in_yt)
    # Every problem `fountain ic` makes gives snapshots that yt opens (a non-cubic box too,
    # through scripts/fountain_yt.py).
    for problem in sod sedov gresho evrard sphere; do
      case $problem in
        sod) n=24 extra="" periodic=true ;;
        sedov) n=8 extra="" periodic=true ;;
        gresho) n=16 extra="" periodic=true ;;
        evrard) n=4 periodic=false extra="gravity:
  enabled: true
  G: 1
  softening_gas: 0.05" ;;
        sphere) n=300 periodic=false extra="gravity:
  enabled: true
  softening_dark_matter: 0.002" ;;
      esac
      "$bin" ic "$problem" -n "$n" -o "$problem.hdf5" > /dev/null 2>&1 || fail "ic $problem"
      cat > params.yml <<EOT
run:
  t_end: 1e-3
  max_steps: 2
initial_conditions:
  file: $problem.hdf5
  periodic: $periodic
output:
  directory: out_$problem
time_integration:
  dt_max: 1e-5
  dt_min: 1e-14
$extra
EOT
      "$bin" run params.yml -q > run.txt 2>&1 || { cat run.txt; fail "run $problem"; }
      "$python" "$root/tests/check_snapshot_yt.py" "out_$problem/snapshot_0001.hdf5" || fail "yt cannot open the $problem snapshot"
    done ;;
  *)
    fail "unknown case $case_name" ;;
esac
echo "PASS: $case_name"
