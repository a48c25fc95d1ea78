# Sourced by the rotating-sphere run scripts: run_or_resume DIR runs DIR/params.yml with
# "$bin" on "$threads" threads, continuing from DIR/restart.hdf5 if a killed run left one,
# and marks DIR done, recording the wall seconds of each piece in DIR/wall_seconds
# (appended: a resumed run has one line per piece).
# A run stopped by SIGTERM (exit status 75, restart file written) is not marked done: the
# script stops there with that status, and running it again continues the run.
# Optional: pid_file (where the running process's id is written) and widen_dir with
# wide_threads: if that directory exists when the run stops with status 75, it was stopped
# to go on with more threads, and it is resumed at once on wide_threads.
run_or_resume() {
  while :; do
    started=$(date +%s)
    status=0
    if [ -f "$1/restart.hdf5" ]; then
      "$bin" run "$1/params.yml" -t "$threads" -q --restart &
    else
      "$bin" run "$1/params.yml" -t "$threads" -q --overwrite &
    fi
    pid=$!
    [ -z "${pid_file:-}" ] || echo "$pid" > "$pid_file"
    wait "$pid" || status=$?
    echo $(($(date +%s) - started)) >> "$1/wall_seconds"
    if [ "$status" -eq 75 ] && [ -n "${widen_dir:-}" ] && [ -d "$widen_dir" ] &&
      [ "$threads" -lt "${wide_threads:-0}" ]; then
      threads=$wide_threads
      echo "== $(basename "$1"): going on with $threads threads"
      continue
    fi
    if [ "$status" -ne 0 ]; then
      echo "$1: stopped (exit status $status); run this script again to continue" >&2
      exit "$status"
    fi
    touch "$1/done"
    return 0
  done
}
