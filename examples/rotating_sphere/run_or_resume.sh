# Sourced by the rotating-sphere run scripts: run_or_resume DIR runs DIR/params.yml with
# "$bin" on "$threads" threads, continuing from DIR/restart.hdf5 if a killed run left one,
# and marks DIR done, recording the wall seconds of this invocation in DIR/wall_seconds
# (appended: a resumed run has one line per piece).
# A run stopped by SIGTERM (exit status 75, restart file written) is not marked done: the
# script stops there with that status, and running it again continues the run.
run_or_resume() {
  started=$(date +%s)
  status=0
  if [ -f "$1/restart.hdf5" ]; then
    "$bin" run "$1/params.yml" -t "$threads" -q --restart || status=$?
  else
    "$bin" run "$1/params.yml" -t "$threads" -q || status=$?
  fi
  echo $(($(date +%s) - started)) >> "$1/wall_seconds"
  if [ "$status" -ne 0 ]; then
    echo "$1: stopped (exit status $status); run this script again to continue" >&2
    exit "$status"
  fi
  touch "$1/done"
}
