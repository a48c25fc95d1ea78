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

# MODE selects the numerical settings of the sphere runs (sets $mode, $dt_min, $limiter,
# $h_min_ratio):
#   paper (the default of the scripts that reproduce the paper's figures): Marri & White (2003)
#            section 3.1: no limiter, dt in [1e-8, 1e-6] (a particle that needs less stops the
#            run, as GADGET does), and the floor of the smoothing length GADGET offers
#            (MinGasHsmlFractional), H_MIN_RATIO times the gas's spline softening length
#            2.8 eps_gas (default 1; 0: no floor; docs/validation.md, "Rotating sphere in the
#            paper's settings", says which floors reach dt_min).
#   fountain: Fountain's defaults: the timestep limiter on (it also wakes the neighbours of
#            particles that feedback heats), no floor of h, and dt_min lowered to 1e-13 so
#            that the dense knots of the cold disc never stop a run.
# out_root: where the mode's runs go (examples/rotating_sphere/output, or its fountain/).
set_mode() {
  mode=${MODE:-paper}
  case $mode in
    paper) dt_min=1.0e-8 limiter=false h_min_ratio=${H_MIN_RATIO:-1} out_root=$here/output ;;
    fountain) dt_min=1.0e-13 limiter=true h_min_ratio=0 out_root=$here/output/fountain ;;
    *) echo "unknown MODE $mode (paper or fountain)" >&2; exit 2 ;;
  esac
}

# make_sphere_ic FILE ARGS...: the rotating sphere's initial conditions, written once; written
# to a temporary name and moved, so that scripts running side by side never read half a file.
make_sphere_ic() {
  ic_file=$1; shift
  [ -f "$ic_file" ] && return 0
  "$bin" ic sphere "$@" -o "$ic_file.$$.tmp"
  mv -f "$ic_file.$$.tmp" "$ic_file"
}
