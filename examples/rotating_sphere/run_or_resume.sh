# Sourced by the rotating-sphere run scripts: run_or_resume DIR runs DIR/params.yml with
# "$bin" on "$threads" threads, continuing from DIR/restart.hdf5 if a killed run left one,
# and marks DIR done.
run_or_resume() {
  if [ -f "$1/restart.hdf5" ]; then
    "$bin" run "$1/params.yml" -t "$threads" -q --restart
  else
    "$bin" run "$1/params.yml" -t "$threads" -q
  fi
  touch "$1/done"
}
