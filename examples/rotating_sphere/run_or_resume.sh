# Sourced by the rotating-sphere run scripts: run_or_resume DIR runs DIR/params.yml with
# "$bin" on "$threads" threads, continuing from DIR/restart.hdf5 if a killed run left one,
# and marks DIR done, recording the wall seconds of this invocation in DIR/wall_seconds
# (appended: a resumed run has one line per piece).
run_or_resume() {
  started=$(date +%s)
  if [ -f "$1/restart.hdf5" ]; then
    "$bin" run "$1/params.yml" -t "$threads" -q --restart
  else
    "$bin" run "$1/params.yml" -t "$threads" -q
  fi
  echo $(($(date +%s) - started)) >> "$1/wall_seconds"
  touch "$1/done"
}
