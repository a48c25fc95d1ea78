#!/bin/sh
# End-to-end checks of the fountain executable: bad input stops it with a clear message and
# a non-zero exit (never a crash); snapshots open in yt; 1 and 2 threads give identical
# snapshots. Usage: cli_tests.sh FOUNTAIN_BINARY REPO_ROOT CASE
. "$(dirname "$0")/cli_prelude.sh"

# The rotating sphere's physics in the tests that run it (parameter-file lines), and its
# star formation with multiphase feedback.
sphere_physics="hydro:
  msph: true
gravity:
  enabled: true
  softening_dark_matter: 0.002
cooling:
  enabled: true"
sphere_feedback="star_formation:
  enabled: true
feedback:
  eps_cold: 0.4
  eps_hot: 0.4"

params() {  # params IC_FILE OUT_DIR [extra yaml]
  cat > params.yml <<EOT
run:
  t_end: ${T_END:-0.002}
initial_conditions:
  file: $1
  periodic: true
output:
  directory: $2
time_integration:
  dt_max: 0.001
  dt_min: 1e-12
${3:-}
EOT
}

# expect_error PATTERN: the run exits with status 2 and prints PATTERN.
expect_error() {
  set +e
  "$bin" run params.yml -q > out.txt 2>&1
  status=$?
  set -e
  [ "$status" -eq 2 ] || { cat out.txt; fail "exit status $status, expected 2"; }
  grep -q -- "$1" out.txt || { cat out.txt; fail "message does not mention '$1'"; }
  echo "ok: $(cat out.txt)"
}

# stop_half_way TOTAL_STEPS COMMAND...: run B (into outB) stopped at half of TOTAL_STEPS as a
# kill would stop it, deterministically (a SIGKILL timed against a run of a few milliseconds is
# a race: the run may be over before it lands). It must leave a restart file, no final snapshot.
stop_half_way() {
  total=$1 half=$(($1 / 2)); shift
  "$@" --abandon-after-steps "$half" > runB.txt 2>&1 || { cat runB.txt; fail "run B"; }
  [ -f outB/restart.hdf5 ] || { cat runB.txt; fail "no restart file was written"; }
  [ ! -f "outB/${last_snapshot:-snapshot_0001}.hdf5" ] || fail "the run ended before it was stopped"
  grep -q "^abandoned after step $half," runB.txt || { cat runB.txt; fail "run B did not stop at step $half"; }
  echo "stopped after $(grep -c '^step' runB.txt) of $total steps; $(grep 'restart file' runB.txt | tail -1)"
}

"$bin" ic sedov -n 8 -o good.hdf5 > /dev/null 2>&1 || fail "cannot write ICs"

case "$case_name" in
  missing_ic)
    params nothere.hdf5 out; expect_error "nothere.hdf5" ;;
  truncated_ic)
    head -c 3000 good.hdf5 > cut.hdf5; params cut.hdf5 out; expect_error "cut.hdf5" ;;
  not_hdf5)
    echo "hello" > text.hdf5; params text.hdf5 out; expect_error "text.hdf5" ;;
  missing_dataset)
    "$python" -c "
import h5py, shutil
shutil.copy('good.hdf5', 'nou.hdf5')
with h5py.File('nou.hdf5', 'a') as f: del f['PartType0/InternalEnergy']"
    params nou.hdf5 out; expect_error "InternalEnergy" ;;
  nan_energy)
    "$python" -c "
import h5py, shutil, numpy as np
shutil.copy('good.hdf5', 'nan.hdf5')
with h5py.File('nan.hdf5', 'a') as f: f['PartType0/InternalEnergy'][5] = np.nan"
    params nan.hdf5 out; expect_error "ID" ;;
  negative_energy)
    "$python" -c "
import h5py, shutil
shutil.copy('good.hdf5', 'negu.hdf5')
with h5py.File('negu.hdf5', 'a') as f: f['PartType0/InternalEnergy'][3] = -1.0"
    params negu.hdf5 out; expect_error "InternalEnergy" ;;
  negative_mass)
    "$python" -c "
import h5py, shutil
shutil.copy('good.hdf5', 'neg.hdf5')
with h5py.File('neg.hdf5', 'a') as f: f['PartType0/Masses'][7] = -1.0"
    params neg.hdf5 out; expect_error "ID" ;;
  zero_particles)
    "$python" -c "
import h5py, numpy as np
with h5py.File('zero.hdf5', 'w') as f:
    h = f.create_group('Header')
    h.attrs['NumPart_ThisFile'] = np.zeros(6, dtype=np.uint32)
    h.attrs['NumPart_Total'] = np.zeros(6, dtype=np.uint32)
    h.attrs['MassTable'] = np.zeros(6)
    h.attrs['BoxSize'] = 1.0
    h.attrs['Time'] = 0.0"
    params zero.hdf5 out; expect_error "zero.hdf5" ;;
  unwritable_output)
    echo "a file" > blocker; params good.hdf5 blocker/out; expect_error "blocker/out" ;;
  disk_full)
    # A full disk while writing: a clear error naming the file, exit status 2 and no crash, no
    # partial file left behind, and nothing lost: the restart file written before is intact
    # and the run continues from it once there is room. A file-size limit stands in for the
    # full disk (with SIGXFSZ ignored, writes past it fail with EFBIG as they would with ENOSPC).
    T_END=0.03 params good.hdf5 out "restart:
  every_steps: 4"
    sed -i 's/^  directory: out$/&\n  delta_time: 0.01/' params.yml
    "$bin" run params.yml --abandon-after-steps 26 > first.txt 2>&1 || { cat first.txt; fail "first run"; }
    [ -f out/restart.hdf5 ] || { cat first.txt; fail "no restart file was written"; }
    cp out/restart.hdf5 restart_before.hdf5
    set +e
    (trap '' XFSZ; ulimit -f 64; exec "$bin" run params.yml -q --restart) > full.txt 2>&1
    status=$?
    set -e
    [ "$status" -eq 2 ] || { cat full.txt; fail "exit status $status on a full disk, expected 2"; }
    grep -q "cannot create .*out/.*hdf5: .*disk full" full.txt || { cat full.txt; fail "the message does not name the file and the cause"; }
    ! ls out/*.tmp > /dev/null 2>&1 || fail "a partial file was left: $(ls out/*.tmp)"
    cmp -s out/restart.hdf5 restart_before.hdf5 || fail "the restart file changed"
    "$bin" run params.yml -q --restart > again.txt 2>&1 || { cat again.txt; fail "restart once there is room"; }
    grep -q "^done" again.txt || { cat again.txt; fail "the restarted run did not finish"; }
    echo "ok: $(head -c 160 full.txt)" ;;
  bad_parameter)
    params good.hdf5 out "hydro:
  gamma: soft"; expect_error "hydro.gamma" ;;
  mpi_hydro_ranks|mpi_gravity_ranks|mpi_collisionless_ranks|mpi_feedback_ranks|mpi_star_formation_ranks|mpi_uneven_ranks)
    # Across MPI ranks the run must give the snapshots of one rank, bit for bit, on 2, 3 and 4
    # ranks (oversubscribed): Sod with the timestep limiter (hydro); an Evrard collapse with
    # self-gravity; a rotating sphere with gravity, cooling, MSPH, star formation with spawning
    # and MFB feedback with promotions. mpi_uneven_ranks: a 4 x 1 x 1 top-level grid on 3 ranks
    # (which do not divide it) and 5 (one owns no cell), with the owners chosen anew at every
    # recut (a repartition in the middle of the run), and cooling on, its snapshots and statistics
    # gathered to rank 0 40 particles a message, and its recuts and exchanges in rounds of
    # 20,000 bytes (about 60 particles, or a few cells); its viscosity is the reconstructed one, so
    # the strain rates and entropies travel with the ghosts' results. The leak checker is off: Open MPI's
    # own allocations outlive MPI_Finalize.
    mpirun_n() { ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np "$@"; }
    extra="" ranks="2 3 4"
    case $case_name in
      mpi_hydro_ranks)
        "$bin" ic sod -n 24 -o ic.hdf5 > /dev/null 2>&1 || fail "cannot write the Sod ICs"
        T_END=0.02 ;;
      mpi_uneven_ranks)
        "$bin" ic sod -n 24 -o ic.hdf5 > /dev/null 2>&1 || fail "cannot write the Sod ICs"
        T_END=0.02 ranks="3 5" extra="space:
  top_cells: 4
domain:
  repartition_imbalance: 0
  repartition_min_steps: 0
  message_bytes: 20000
cooling:
  enabled: true
hydro:
  viscosity_reconstruction: true
output:
  statistics_every: 4
  gather_particles: 40" ;;
      mpi_gravity_ranks)
        # 7,208 particles on 4 x 4 x 4 top cells: every rank owns some, and each assembles its
        # gravity tree with parts of the others' (halo mode: gas only, open boundaries). The
        # reconstructed viscosity: its strain rates also come back from the restart set.
        "$bin" ic evrard -n 12 -o ic.hdf5 > /dev/null 2>&1 || fail "cannot write the Evrard ICs"
        T_END=0.05 extra="gravity:
  enabled: true
  softening_gas: 0.01
  G: 1
hydro:
  viscosity_reconstruction: true
space:
  top_cells: 4" ;;
      mpi_collisionless_ranks)
        # The rotating sphere's gas and dark matter (2,000 of each) with gravity, cooling and
        # MSPH, no star formation, on 4 x 4 x 4 top cells: halo mode, each rank holding only its
        # own leaves' dark matter; statistics summed 40 particles a message.
        "$bin" ic sphere -n 2000 -o ic.hdf5 > /dev/null 2>&1 || fail "cannot write the sphere ICs"
        T_END=3e-4 extra="$sphere_physics
space:
  top_cells: 4
output:
  statistics_every: 5
  gather_particles: 40" ;;
      mpi_feedback_ranks)
        "$bin" ic sphere -n 300 -o ic.hdf5 > /dev/null 2>&1 || fail "cannot write the sphere ICs"
        T_END=6e-4 extra="$sphere_feedback
$sphere_physics" ;;
      mpi_star_formation_ranks)
        # Star formation without feedback sites (the paper's SPH and MSPH runs) in halo mode:
        # conversion in each owner's leaves, spawning and dissolving in turns of the owners of
        # the particles due, the owners chosen anew at every recut, on 4 x 4 x 4 top cells.
        "$bin" ic sphere -n 300 -o ic.hdf5 > /dev/null 2>&1 || fail "cannot write the sphere ICs"
        T_END=6e-4 extra="star_formation:
  enabled: true
feedback:
  eps_cold: 0
  eps_hot: 0
$sphere_physics
space:
  top_cells: 4
domain:
  repartition_imbalance: 0
  repartition_min_steps: 0
output:
  statistics_every: 5" ;;
    esac
    write_params() {  # write_params OUT_DIR
      params ic.hdf5 "$1" "$extra"
      if [ "$case_name" != mpi_hydro_ranks ] && [ "$case_name" != mpi_uneven_ranks ]; then
        sed -i 's/periodic: true/periodic: false/; s/dt_max: 0.001/dt_max: 1e-5/; s/dt_min: 1e-12/dt_min: 1e-14/' params.yml
        if [ "$case_name" = mpi_gravity_ranks ]; then sed -i 's/dt_max: 1e-5/dt_max: 0.001/' params.yml; fi
      fi
    }
    restarts_across_ranks() {  # STEPS: stopped there as a kill would stop it, each run ends as the 1-rank one
      write_params outB
      printf 'restart:\n  every_steps: 4\n' >> params.yml
      mpirun_n 2 "$bin" run params.yml -q -t 1 --abandon-after-steps "$1" > killed.txt 2>&1 || { cat killed.txt; fail "2-rank run to be stopped"; }
      grep -q "^abandoned after step $1" killed.txt || { cat killed.txt; fail "the 2-rank run did not stop at step $1"; }
      ls outB/restart_*_rank1.hdf5 > /dev/null || fail "the 2-rank run wrote no restart set"
      mpirun_n 3 "$bin" run params.yml -q -t 1 --restart > restarted.txt 2>&1 || { cat restarted.txt; fail "restart on 3 ranks"; }
      "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0001.hdf5 outB/snapshot_0001.hdf5
      write_params outC
      printf 'restart:\n  every_steps: 4\n' >> params.yml
      "$bin" run params.yml -q -t 1 --abandon-after-steps "$1" > killed.txt 2>&1 || { cat killed.txt; fail "1-rank run to be stopped"; }
      mpirun_n 2 "$bin" run params.yml -q -t 1 --restart > restarted.txt 2>&1 || { cat restarted.txt; fail "restart on 2 ranks"; }
      "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0001.hdf5 outC/snapshot_0001.hdf5
    }
    write_params out1
    "$bin" run params.yml -q -t 1 > run1.txt 2>&1 || { cat run1.txt; fail "1-rank run"; }
    for n in $ranks; do
      write_params "out$n"
      mpirun_n "$n" "$bin" run params.yml -q -t 1 > "run$n.txt" 2>&1 || { cat "run$n.txt"; fail "$n-rank run"; }
      grep "^ranks: $n" "run$n.txt" || { cat "run$n.txt"; fail "no rank summary from the $n-rank run"; }
      [ ! -e "out$n/snapshot_0002.hdf5" ] || fail "more snapshots than the 1-rank run"
      "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0001.hdf5 "out$n/snapshot_0001.hdf5"
      if [ "$case_name" = mpi_hydro_ranks ]; then
        # Sod runs in halo mode: rank 0 must have held stale copies of some leaves (the
        # snapshot comparison above then shows they never leaked into the results).
        kept=$(sed -n "s/^halo mode: rank 0 kept \([0-9.]*\)%.*/\1/p" "run$n.txt")
        [ -n "$kept" ] || { cat "run$n.txt"; fail "the $n-rank Sod run did not run in halo mode"; }
        awk -v k="$kept" 'BEGIN { exit !(k < 100) }' || fail "rank 0 kept every leaf current ($kept%): no stale copy was tested"
        echo "$n ranks: rank 0 kept $kept% of the leaves current"
      fi
      if [ "$case_name" = mpi_gravity_ranks ]; then
        # Self-gravitating gas runs in halo mode, each rank's tree assembled across ranks.
        grep "^halo mode: rank 0 kept" "run$n.txt" || { cat "run$n.txt"; fail "the Evrard run was not in halo mode"; }
        received=$(sed -n 's/^gravity tree: .* and \([0-9.e+]*\) sources a time.*/\1/p' "run$n.txt")
        awk -v r="$received" 'BEGIN { exit !(r > 0) }' || { cat "run$n.txt"; fail "rank 0 received no other rank's sources"; }
      fi
      if [ "$case_name" = mpi_collisionless_ranks ]; then
        grep "^halo mode: rank 0 kept" "run$n.txt" || { cat "run$n.txt"; fail "the sphere was not run in halo mode"; }
        cmp out1/statistics.txt "out$n/statistics.txt" || fail "statistics differ from the 1-rank run's"
      fi
      if [ "$case_name" = mpi_star_formation_ranks ]; then
        grep "^halo mode: rank 0 kept" "run$n.txt" || { cat "run$n.txt"; fail "the star-forming sphere was not run in halo mode"; }
        cmp out1/statistics.txt "out$n/statistics.txt" || fail "statistics differ from the 1-rank run's"
        line=$(grep "^star formation across ranks:" "run$n.txt") || { cat "run$n.txt"; fail "no spawning or dissolving across ranks"; }
        echo "$n ranks: $line"
        # Several owners' turns in one step, and dissolved gas given to another rank's particles.
        turns=$(echo "$line" | sed 's/.* in \([0-9]*\) turns over \([0-9]*\) steps; \([0-9]*\) shares.*/\1 \2 \3/')
        echo "$turns" | awk '{ exit !($1 > $2 && $3 > 0) }' && crossed=yes
      fi
      if [ "$case_name" = mpi_feedback_ranks ]; then
        # Each rank assembling its gravity tree from its own subtrees and the other ranks' parts
        # gives the same bits as every rank building the whole tree.
        write_params "outtree$n"
        printf 'domain:\n  assemble_gravity_tree: true\n' >> params.yml
        mpirun_n "$n" "$bin" run params.yml -q -t 1 > "runtree$n.txt" 2>&1 || { cat "runtree$n.txt"; fail "$n-rank run, assembled tree"; }
        grep "^gravity tree: assembled on each rank" "runtree$n.txt" || { cat "runtree$n.txt"; fail "the tree was not assembled across ranks"; }
        "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0001.hdf5 "outtree$n/snapshot_0001.hdf5"
      fi
      if [ "$case_name" = mpi_uneven_ranks ]; then
        chosen=$(sed -n "s/^ranks: $n, cell owners chosen \([0-9]*\) times.*/\1/p" "run$n.txt")
        [ "$chosen" -gt 1 ] || fail "owners were chosen only $chosen times: no repartition mid-run"
        # With cooling, in halo mode: the radiated energy (which the owners' wakes add to) and
        # every other total of the statistics file, line for line.
        cmp out1/statistics.txt "out$n/statistics.txt" || fail "statistics differ from the 1-rank run's"
        # A cut stands until domain.repartition_min_steps have passed: in this short run the
        # first cut, from particle counts, is never judged.
        write_params "outmin$n"
        sed -i 's/repartition_min_steps: 0/repartition_min_steps: 1000000/' params.yml
        mpirun_n "$n" "$bin" run params.yml -q -t 1 > "runmin$n.txt" 2>&1 || { cat "runmin$n.txt"; fail "$n-rank run, long span"; }
        chosen_min=$(sed -n "s/^ranks: $n, cell owners chosen \([0-9]*\) times.*/\1/p" "runmin$n.txt")
        [ "$chosen_min" = 1 ] || fail "owners chosen $chosen_min times with a span of 1000000 steps (expected once)"
        "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0001.hdf5 "outmin$n/snapshot_0001.hdf5"
        echo "$n ranks: owners chosen $chosen times at every recut, $chosen_min with a long span"
      fi
    done
    if [ "$case_name" = mpi_collisionless_ranks ]; then
      # A 2-rank restart set (each piece its own leaves' dark matter, with their places) read
      # on 3 ranks, and a file written whole by one rank read on 2.
      restarts_across_ranks 250
    fi
    if [ "$case_name" = mpi_star_formation_ranks ]; then
      [ "${crossed:-}" = yes ] || fail "no rank count had events of several owners in a step and shares across ranks"
      "$python" -c "
import h5py, sys
with h5py.File('out1/snapshot_0001.hdf5', 'r') as f, h5py.File('ic.hdf5', 'r') as ic:
    stars = f['PartType4/Coordinates'].shape[0] if 'PartType4' in f else 0
    gone = ic['PartType0/Coordinates'].shape[0] - f['PartType0/Coordinates'].shape[0]
    sys.exit(0 if stars > 0 and gone > 0 else 1)" || fail "no star particle was spawned or no gas dissolved"
      # A 2-rank restart set, stars and all, read on 3 ranks, and a 1-rank file on 2.
      restarts_across_ranks 1000
    fi
    if [ "$case_name" = mpi_gravity_ranks ]; then
      # Stopped half-way on 2 ranks as a kill would stop it, the run continues from its
      # restart set on 3 ranks as the uninterrupted 1-rank run ends.
      write_params outB
      printf 'restart:\n  every_steps: 4\n' >> params.yml
      mpirun_n 2 "$bin" run params.yml -q -t 1 --abandon-after-steps 30 > killed.txt 2>&1 || { cat killed.txt; fail "2-rank run to be stopped"; }
      grep -q "^abandoned after step 30" killed.txt || { cat killed.txt; fail "the 2-rank run did not stop at step 30"; }
      mpirun_n 3 "$bin" run params.yml -q -t 1 --restart > restarted.txt 2>&1 || { cat restarted.txt; fail "restart on 3 ranks"; }
      "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0001.hdf5 outB/snapshot_0001.hdf5
    fi
    if [ "$case_name" = mpi_feedback_ranks ]; then
      "$python" -c "
import h5py, sys
with h5py.File('out1/snapshot_0001.hdf5', 'r') as f:
    sys.exit(0 if 'PartType4' in f and f['PartType4/Coordinates'].shape[0] > 0 else 1)" || fail "no star particle was spawned"
    fi ;;
  mpi_shared_input)
    # Across ranks that read the gas in shares (Sod: no gravity), bad input is still named as
    # one rank names it: two particles of different shares at one point (every rank names the
    # same pair), a bad mass in the last share, an ID repeated far from its first use.
    mpirun_n() { ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np "$@"; }
    "$bin" ic sod -n 24 -o good.hdf5 > /dev/null 2>&1 || fail "cannot write the Sod ICs"
    "$python" -c "
import h5py, shutil
for name in ('same', 'mass', 'ids'):
    shutil.copy('good.hdf5', name + '.hdf5')
with h5py.File('same.hdf5', 'a') as f:
    x = f['PartType0/Coordinates']; x[-5] = x[10]
with h5py.File('mass.hdf5', 'a') as f:
    m = f['PartType0/Masses']; m[-2] = -1.0
with h5py.File('ids.hdf5', 'a') as f:
    i = f['PartType0/ParticleIDs']; i[-3] = i[4]
with h5py.File('good.hdf5', 'r') as f:
    ids = f['PartType0/ParticleIDs'][:]
    open('ids.txt', 'w').write('%d %d %d %d\n' % (ids[10], ids[-5], ids[-2], ids[4]))"
    read a b m r < ids.txt
    refused_by() {  # refused_by PATTERN RANKS
      params "$3" out "" > /dev/null
      set +e
      if [ "$2" = 1 ]; then "$bin" run params.yml -q > out.txt 2>&1; else mpirun_n "$2" "$bin" run params.yml -q > out.txt 2>&1; fi
      status=$?
      set -e
      [ "$status" -ne 0 ] || { cat out.txt; fail "$3 on $2 ranks ran"; }
      grep -q -- "$1" out.txt || { cat out.txt; fail "$3 on $2 ranks: the message does not mention '$1'"; }
      echo "ok ($3, $2 ranks): $(grep -m1 -- "$1" out.txt)"
    }
    for n in 1 3; do
      refused_by "same.hdf5: gas particles ID $a and ID $b lie at the same position" "$n" same.hdf5
      refused_by "particle ID $m has mass -1" "$n" mass.hdf5
      refused_by "particle ID $r appears more than once" "$n" ids.hdf5
    done ;;
  mpi_restart_after_kill)
    # A 2-rank run stopped half-way after a restart set, as a kill would stop it, and
    # restarted on 1, 2 and 3 ranks, ends as the uninterrupted 1-rank run does, bit for bit.
    extra="restart:
  every_steps: 4"
    "$bin" ic sod -n 24 -o ic.hdf5 > /dev/null 2>&1 || fail "cannot write the Sod ICs"
    T_END=0.05 params ic.hdf5 outA "$extra"; cp params.yml params_mpi_whole.yml
    T_END=0.05 params ic.hdf5 outB "$extra"; cp params.yml params_mpi_killed.yml
    "$bin" run params_mpi_whole.yml > runA.txt 2>&1 || { cat runA.txt; fail "uninterrupted run"; }
    stop_half_way "$(grep -c '^step' runA.txt)" \
      env ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np 2 "$bin" run params_mpi_killed.yml
    # The restart is a set: a piece per rank, named by the master (restart.hdf5), and no other.
    pieces=$(ls outB | grep -c '^restart_[0-9]*_rank[0-9]*\.hdf5$' || true)
    [ "$pieces" -eq 2 ] || { ls outB; fail "expected 2 restart pieces beside the master, found $pieces"; }
    # The same set continues on 1 and on 3 ranks too (copies of the run folder).
    for n in 1 3; do
      cp -r outB "outB$n"
      sed "s|directory: outB|directory: outB$n|" params_mpi_killed.yml > "params_mpi_$n.yml"
      ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np "$n" "$bin" run "params_mpi_$n.yml" --restart \
        > "restart$n.txt" 2>&1 || { cat "restart$n.txt"; fail "restart of the 2-rank set on $n ranks failed"; }
      "$python" "$root/tests/compare_snapshots.py" outA/snapshot_0001.hdf5 "outB$n/snapshot_0001.hdf5"
    done
    ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np 2 "$bin" run params_mpi_killed.yml --restart \
      > restart.txt 2>&1 || { cat restart.txt; fail "restart on 2 ranks failed"; }
    head -1 restart.txt
    "$python" "$root/tests/compare_snapshots.py" outA/snapshot_0001.hdf5 outB/snapshot_0001.hdf5
    # A later set replaced the first: still two pieces, and those the master names.
    pieces=$(ls outB | grep -c '^restart_[0-9]*_rank[0-9]*\.hdf5$' || true)
    [ "$pieces" -eq 2 ] || { ls outB; fail "stale restart pieces left: $pieces" ; }
    # On 2 ranks each reads only its pieces: a set whose pieces do not fill the run (the second
    # a copy of the first, checksum and all) is still refused, with how much they hold.
    cp -r outB outBdup
    first_piece=$(ls outBdup/restart_*_rank0.hdf5)
    cp "$first_piece" "$(ls outBdup/restart_*_rank1.hdf5)"
    sed "s|directory: outB|directory: outBdup|" params_mpi_killed.yml > params_mpi_dup.yml
    set +e
    ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np 2 "$bin" run params_mpi_dup.yml --restart \
      > dup.txt 2>&1
    status=$?
    set -e
    [ "$status" -ne 0 ] || { cat dup.txt; fail "a set with a repeated piece was restarted"; }
    grep -q "restart.hdf5: its pieces hold [0-9]* of [0-9]* gas" dup.txt || { cat dup.txt; fail "no message on the repeated piece"; }
    echo "ok: $(grep -m1 'its pieces hold' dup.txt)"
    # On 1 rank the run writes one whole file again, and the 3-rank copy's set was replaced.
    [ "$(ls outB1 | grep -c '_rank' || true)" -eq 0 ] || { ls outB1; fail "pieces left beside a 1-rank restart file"; } ;;
  comoving_music_yt|comoving_music_bitwise|comoving_music_restart)
    # A comoving run from another code's initial conditions: MUSIC's GADGET binary zoom (gas,
    # high-resolution dark matter, and type-5 coarse particles, GADGET's
    # velocity convention and 1e10 Msun/h mass unit) at z = 49, periodic TreePM, to a = 0.03
    # with snapshots at the listed redshifts. _yt: yt opens the snapshots as a cosmological data
    # set at their redshift with the header's cosmology and the gas and dark matter masses.
    # _bitwise: 1 and 2 threads and 2, 3 and 4 ranks give the same bits. _restart: a run stopped
    # half-way and restarted ends as the uninterrupted one, bit for bit.
    cp "$root/tests/data/music/zoom_gadget2.dat" music.dat
    cparams() {  # cparams OUT_DIR [extra yaml]
      cat > params.yml <<EOT
initial_conditions:
  file: music.dat
  periodic: true
cosmology:
  enabled: true
  omega_m: 0.3
  omega_lambda: 0.7
  omega_b: 0.03
  hubble_param: 0.6
  a_end: 0.03
gravity:
  enabled: true
  softening_dark_matter: 0.05
time_integration:
  dt_max: 1
output:
  directory: $1
  redshifts: [45, 40]
${2:-}
EOT
    }
    case $case_name in
      comoving_music_yt)
        cparams out
        "$bin" run params.yml > run.txt 2>&1 || { cat run.txt; fail "comoving run failed"; }
        grep -q "^snapshot out/snapshot_0001.hdf5 at a = 0.0217391 (z = 45)" run.txt || { cat run.txt; fail "no snapshot at z = 45"; }
        grep -q "^done: .* steps to a = 0.03, 4 snapshots" run.txt || { tail -3 run.txt; fail "the run did not end at a = 0.03"; }
        for k in 0 3; do "$python" "$root/tests/check_snapshot_yt.py" "out/snapshot_000$k.hdf5"; done
        "$python" -c "
import h5py, sys
with h5py.File('out/snapshot_0003.hdf5', 'r') as f:
    n = f['Header'].attrs['NumPart_ThisFile']
    m = [f[f'PartType{t}/Masses'][:] for t in (0, 1, 2)]
    # One coarse level below the fine one: each coarse particle is 8 fine cells' matter.
    ratio = m[2].max() / (m[0].max() + m[1].max())
    ok = n[0] > 0 and n[1] > 0 and n[2] > 0 and m[2].min() == m[2].max() and abs(ratio - 8) < 1e-6 and f['Header'].attrs['Time'] == 0.03
    sys.exit(0 if ok else 1)" || fail "the snapshot lacks a particle type, the coarse masses or the time" ;;
      comoving_music_bitwise)
        cparams out1; "$bin" run params.yml -q -t 1 > run1.txt 2>&1 || { cat run1.txt; fail "1-thread run"; }
        cparams out2; "$bin" run params.yml -q -t 2 > run2.txt 2>&1 || { cat run2.txt; fail "2-thread run"; }
        "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0003.hdf5 out2/snapshot_0003.hdf5
        # Across ranks the mesh is shared as FFTW's slabs: rank 0 holds ceil(N / ranks) of its N
        # planes, and the run still gives one rank's bits (3 ranks leave the last a short slab;
        # there the mesh's particles and the halo's cells travel in rounds of 2,000 bytes).
        for n in 2 3 4; do
          extra=""
          [ "$n" -eq 3 ] && extra="domain:
  message_bytes: 2000"
          cparams "outr$n" "$extra"; ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np "$n" "$bin" run params.yml -q -t 1 \
            > "runr$n.txt" 2>&1 || { cat "runr$n.txt"; fail "$n-rank run"; }
          "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0003.hdf5 "outr$n/snapshot_0003.hdf5"
          line=$(grep "^mesh: " "runr$n.txt") || { cat "runr$n.txt"; fail "no mesh line from the $n-rank run"; }
          cells=$(echo "$line" | sed -n 's/^mesh: \([0-9]*\)^3 in '"$n"' slabs; rank 0 held \([0-9]*\) planes.*/\1/p')
          planes=$(echo "$line" | sed -n 's/^mesh: \([0-9]*\)^3 in '"$n"' slabs; rank 0 held \([0-9]*\) planes.*/\2/p')
          [ -n "$cells" ] && [ "$planes" -eq $(( (cells + n - 1) / n )) ] || fail "rank 0 of $n held the wrong planes: $line"
          echo "$n ranks: $line"
        done ;;
      comoving_music_restart)
        cparams outA; cp params.yml paramsA.yml
        cparams outB "restart:
  every_steps: 8"; cp params.yml paramsB.yml
        "$bin" run paramsA.yml > runA.txt 2>&1 || { cat runA.txt; fail "uninterrupted run"; }
        last_snapshot=snapshot_0003 stop_half_way "$(grep -c '^step' runA.txt)" "$bin" run paramsB.yml
        "$bin" run paramsB.yml --restart > restart.txt 2>&1 || { cat restart.txt; fail "restart failed"; }
        head -1 restart.txt
        for k in 1 2 3; do "$python" "$root/tests/compare_snapshots.py" "outA/snapshot_000$k.hdf5" "outB/snapshot_000$k.hdf5"; done
        # Across ranks (halo mode): a 2-rank set, each piece its own cells' gas and dark matter
        # of both masses with their places, continued on 3 ranks.
        cparams outC "restart:
  every_steps: 8"
        half=$(( $(grep -c '^step' runA.txt) / 2 ))
        ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np 2 "$bin" run params.yml -q -t 1 \
          --abandon-after-steps "$half" > killedC.txt 2>&1 || { cat killedC.txt; fail "2-rank run to be stopped"; }
        ls outC/restart_*_rank1.hdf5 > /dev/null || fail "the 2-rank run wrote no restart set"
        ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np 3 "$bin" run params.yml -q -t 1 --restart \
          > restartC.txt 2>&1 || { cat restartC.txt; fail "restart on 3 ranks"; }
        grep -q "^halo mode: rank 0 kept" restartC.txt || { cat restartC.txt; fail "the 3-rank run was not in halo mode"; }
        for k in 1 2 3; do "$python" "$root/tests/compare_snapshots.py" "outA/snapshot_000$k.hdf5" "outC/snapshot_000$k.hdf5"; done ;;
    esac ;;
  comoving_galaxy_bitwise|comoving_galaxy_restart)
    # A small cosmological box (2 x 16^3 in 2 Mpc/h, z = 49) with everything a galaxy run
    # has: cooling, star formation, MSPH and multiphase feedback, to a = 0.16, by which time
    # stars have been spawned and reservoirs promoted. _bitwise: 1 and 2 threads and 2 ranks
    # give the same bits; _restart: a run stopped half-way and restarted ends as the
    # uninterrupted one.
    "$bin" ic cosmo -n 16 --box 2 --omega-b 0.03 --hubble 0.6 --seed 3 -o box.hdf5 > ic.txt 2>&1 || { cat ic.txt; fail "ic cosmo"; }
    gparams() {  # gparams OUT_DIR [extra yaml]
      cat > params.yml <<EOT
initial_conditions:
  file: box.hdf5
  periodic: true
cosmology:
  enabled: true
  omega_b: 0.03
  hubble_param: 0.6
  a_end: 0.16
gravity:
  enabled: true
  softening_dark_matter: 0.006
  softening_max_physical: 0.003
hydro:
  msph: true
cooling:
  enabled: true
star_formation:
  enabled: true
feedback:
  eps_cold: 0.4
  eps_hot: 0.4
time_integration:
  dt_max: 1
output:
  directory: $1
  statistics_every: 20
  scale_factors: [0.1]
  fof_groups: true
  hop_groups: true
${2:-}
EOT
    }
    gparams outA; "$bin" run params.yml -t 2 > runA.txt 2>&1 || { cat runA.txt; fail "2-thread run"; }
    "$python" -c "
import h5py, sys
with h5py.File('outA/snapshot_0002.hdf5', 'r') as f:
    ok = f['Header'].attrs['NumPart_ThisFile'][4] > 0 and f['PartType0/Promoted'][:].sum() > 0
    born = f['PartType4/BirthTime']
    ok = ok and 0.1 < born[:].min() and born[:].max() <= 0.16 and born.attrs['a-scale exponent'][0] == 0
    sys.exit(0 if ok else 1)" || fail "no star particle born near a = 0.16, or nothing promoted: the test would prove little"
    if [ "$case_name" = comoving_galaxy_bitwise ]; then
      gparams out1; "$bin" run params.yml -q -t 1 > run1.txt 2>&1 || { cat run1.txt; fail "1-thread run"; }
      "$python" "$root/tests/compare_snapshots.py" outA/snapshot_0002.hdf5 out1/snapshot_0002.hdf5
      # On 2 ranks (the mesh in slabs, its messages ordered with star formation's).
      gparams outr; ASAN_OPTIONS=detect_leaks=0 mpirun --allow-run-as-root --oversubscribe -np 2 "$bin" run params.yml -q -t 1 \
        > runr.txt 2>&1 || { cat runr.txt; fail "2-rank run"; }
      "$python" "$root/tests/compare_snapshots.py" outA/snapshot_0002.hdf5 outr/snapshot_0002.hdf5
      # The catalogues written beside the snapshots (output.fof_groups, output.hop_groups).
      "$python" - <<'EOT' || fail "the in-run catalogues differ or are empty"
import h5py, numpy as np, sys
ok = True
for name in ('fof_0002.hdf5', 'hop_0002.hdf5'):
    a, b = h5py.File('outA/' + name, 'r'), h5py.File('out1/' + name, 'r')
    ok = ok and a['Header'].attrs['Ngroups_Total'] > 0
    for d in ('Group/GroupLen', 'Group/GroupMass', 'IDs/ID'):
        ok = ok and np.array_equal(a[d][:], b[d][:])
sys.exit(0 if ok else 1)
EOT
      # The group finders on 2 ranks, each with its own particles, and `fountain fof` and
      # `fountain hop` on the snapshot: the one-process run's catalogues, every dataset bit for bit.
      "$bin" fof outA/snapshot_0002.hdf5 -o fof_offline.hdf5 > fof_offline.txt 2>&1 || { cat fof_offline.txt; fail "fof"; }
      "$bin" hop outA/snapshot_0002.hdf5 -o hop_offline.hdf5 > hop_offline.txt 2>&1 || { cat hop_offline.txt; fail "hop"; }
      "$python" - <<'EOT' || fail "the catalogues of 1 and 2 ranks, or in the run and from its snapshot, differ"
import h5py, numpy as np, sys
ok = True
for kind in ('fof', 'hop'):
    ref = h5py.File('outA/%s_0002.hdf5' % kind, 'r')
    names = []
    ref.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
    ok = ok and ref['Header'].attrs['Ngroups_Total'] > 0 and len(names) >= 11
    for other in ('outr/%s_0002.hdf5' % kind, '%s_offline.hdf5' % kind):
        f = h5py.File(other, 'r')
        for n in names:
            if not np.array_equal(ref[n][:], f[n][:], equal_nan=True):
                print(other, n, 'differs'); ok = False
        for k, v in ref['Header'].attrs.items():
            if k != 'Snapshot' and not np.array_equal(np.asarray(v), np.asarray(f['Header'].attrs[k])):
                print(other, 'Header', k, 'differs'); ok = False
sys.exit(0 if ok else 1)
EOT
    else
      gparams outB "restart:
  every_steps: 50"
      last_snapshot=snapshot_0002 stop_half_way "$(grep -c '^step' runA.txt)" "$bin" run params.yml -t 2
      "$bin" run params.yml -t 2 --restart > restart.txt 2>&1 || { cat restart.txt; fail "restart failed"; }
      head -1 restart.txt
      "$python" "$root/tests/compare_snapshots.py" outA/snapshot_0002.hdf5 outB/snapshot_0002.hdf5
    fi ;;
  reference_tables)
    # `fountain reference`: the background table against Einstein-de Sitter's closed forms
    # and the published LCDM values (COSMOLOGY.md C2), the Ewald tables against the published
    # correction field and convergence; bad ranges and unwritable files are named.
    "$bin" reference background --omega-m 1 --omega-lambda 0 --a-begin 0.01 --points 50 -o eds.txt > log.txt 2>&1 ||
      { cat log.txt; fail "reference background (EdS)"; }
    "$bin" reference background --a-begin 0.02 --points 30 -o lcdm.txt > log.txt 2>&1 ||
      { cat log.txt; fail "reference background (LCDM)"; }
    "$bin" reference ewald --points 200 --line-points 11 -o ewald > log.txt 2>&1 || { cat log.txt; fail "reference ewald"; }
    cat log.txt
    "$python" - <<'EOT' || fail "the reference tables are wrong"
import numpy as np, sys
t = np.loadtxt('eds.txt')
a, H0 = t[:, 0], 100.0
exact = [1 / a - 1, a**-1.5, 2 / (3 * H0) * a**1.5, a, np.ones_like(a), -3 / 7 * a**2, 2 * np.ones_like(a),
         2 / H0 * (10 - a**-0.5), 2 / H0 * (a**0.5 - 0.1), 2 / H0 * (10 - a**-0.5), 2 / (3 * H0) * (a**1.5 - 1e-3)]
worst = max(np.abs(t[:, c + 1] - e).max() / np.abs(e).max() for c, e in enumerate(exact))
l = np.loadtxt('lcdm.txt')[-1]
# a = 1: H0 t0, D, f, D2 / (-3/7 D^2), f2, and the factors from a = 0.02 (C2.1-C2.3).
got = [H0 * l[3], l[4], l[5], l[6] / (-3 / 7 * l[4] ** 2), l[7], l[8], l[9], l[11]]
want = [0.9640994, 0.7789810168, 0.5127962477, 1.00863056, 1.04044783, 0.2163879, 0.02788679, 9.606567e-3]
lcdm = max(abs(g / w - 1) for g, w in zip(got, want))
p = np.loadtxt('ewald/published.txt')
ew = max(abs(p[0, 6] - 2.8372975), np.abs(p[1, 3:6] - [1.2464596, 0, 0]).max(),
         np.abs(p[2, 3:6] - [0.2128998, 0.5644484, 1.2980756]).max(), np.abs(p[5, 3:6] - 0.7698004).max())
c = np.loadtxt('ewald/convergence.txt')
row = lambda n, h2, alpha=2.0: c[(c[:, 0] == n) & (c[:, 1] == h2) & (c[:, 2] == alpha)][0, 3]
conv = [row(2, 4), row(3, 8), row(4, 10), row(8, 64, 1.5)]
print(f"EdS table within {worst:.1e} of the closed forms, LCDM within {lcdm:.1e} of the published values, "
      f"Ewald within {ew:.1e}; cuts (2, 4), (3, 8), (4, 10), alpha 1.5: {conv}")
ok = worst < 1e-10 and lcdm < 2e-7 and ew < 1e-7
ok = ok and 1e-5 < conv[0] < 1e-4 and 1e-10 < conv[1] < 1e-8 and 1e-12 < conv[2] < 1e-10 and conv[3] < 1e-13
sys.exit(0 if ok else 1)
EOT
    set +e
    "$bin" reference background --a-begin 0.5 --a-end 0.1 -o x.txt > bad.txt 2>&1; status=$?
    set -e
    [ "$status" -eq 2 ] && grep -q "a-begin" bad.txt || { cat bad.txt; fail "a reversed range was not refused"; }
    set +e
    "$bin" reference background -o nothere/x.txt > bad.txt 2>&1; status=$?
    set -e
    [ "$status" -eq 2 ] && grep -q "nothere/x.txt" bad.txt || { cat bad.txt; fail "an unwritable table was not named"; } ;;
  fof_catalogue)
    # `fountain fof` on a dark matter snapshot written to GADGET's layout: two Plummer clumps
    # (one across the box's corner) in a uniform background. Two groups, the larger first, the
    # linking length 0.2 of the mean spacing (from the mean mass and Omega_m rho_crit0), the
    # same catalogue on 1 and 2 threads; bad input is named.
    "$python" - <<'EOT'
import h5py, numpy as np
rng = np.random.default_rng(4)
box, n_bg = 10.0, 4096
def plummer(n, b):
    r = b / np.sqrt(rng.random(n) ** (-2.0 / 3.0) - 1.0)
    r = r[r < 10 * b][: n]
    v = rng.normal(size=(len(r), 3))
    return v / np.linalg.norm(v, axis=1)[:, None] * r[:, None]
x = np.concatenate([rng.random((n_bg, 3)) * box, plummer(3000, 0.05) + 5.0, plummer(2000, 0.04)]) % box
n = len(x)
rho_crit = 3 * 100.0**2 / (8 * np.pi * 4.300917270069976e-09)
m = 0.3 * rho_crit * box**3 / n
with h5py.File('dm.hdf5', 'w') as f:
    h = f.create_group('Header')
    h.attrs['NumPart_ThisFile'] = np.array([0, n, 0, 0, 0, 0], dtype=np.uint64)
    h.attrs['MassTable'] = np.array([0, m, 0, 0, 0, 0], dtype=float)
    h.attrs['BoxSize'] = box
    h.attrs['Time'] = 1.0
    h.attrs['Omega0'] = 0.3
    h.attrs['OmegaLambda'] = 0.7
    h.attrs['HubbleParam'] = 0.7
    g = f.create_group('PartType1')
    g['Coordinates'] = x
    g['Velocities'] = np.zeros_like(x)
    g['ParticleIDs'] = np.arange(1, n + 1, dtype=np.uint64)
EOT
    "$bin" fof dm.hdf5 -o g1.hdf5 -t 1 > fof1.txt 2>&1 || { cat fof1.txt; fail "fof on 1 thread"; }
    "$bin" fof dm.hdf5 -o g2.hdf5 -t 2 > fof2.txt 2>&1 || { cat fof2.txt; fail "fof on 2 threads"; }
    cat fof2.txt
    "$python" - <<'EOT' || fail "the catalogue is wrong"
import h5py, numpy as np, sys
a, b = h5py.File('g1.hdf5', 'r'), h5py.File('g2.hdf5', 'r')
n = a['Header'].attrs['Ngroups_Total']
spacing = 10.0 / h5py.File('dm.hdf5', 'r')['Header'].attrs['NumPart_ThisFile'][1] ** (1 / 3)
ok = n == 2 and abs(a['Header'].attrs['LinkingLength'] / (0.2 * spacing) - 1) < 1e-5
length = a['Group/GroupLen'][:]
ok = ok and length[0] > length[1] > 1500 and length[0] > 2500
pos = a['Group/GroupPos'][:]
ok = ok and np.abs(pos[0] - 5.0).max() < 0.05 and np.abs((pos[1] + 5) % 10 - 5).max() < 0.05
for name in ['Group/GroupLen', 'Group/GroupMass', 'Group/GroupPos', 'Group/Group_M_Crit200', 'IDs/ID']:
    ok = ok and np.array_equal(a[name][:], b[name][:])
sys.exit(0 if ok else 1)
EOT
    set +e
    "$bin" fof nothere.hdf5 -o g.hdf5 > bad.txt 2>&1; status=$?
    set -e
    [ "$status" -eq 2 ] && grep -q "nothere.hdf5" bad.txt || { cat bad.txt; fail "a missing snapshot was not named"; }
    set +e
    "$bin" fof dm.hdf5 -o g.hdf5 -b 0.2 --linking-length 0.1 > bad.txt 2>&1; status=$?
    set -e
    [ "$status" -eq 2 ] && grep -q "give one" bad.txt || { cat bad.txt; fail "two linking lengths were not refused"; }
    # `fountain mass-function` on that catalogue: its counts are the groups' FOF masses binned,
    # the fits' expected counts positive and falling with mass; bad bins are refused.
    "$bin" mass-function g1.hdf5 --log-min 12 --log-max 14.5 --bin-width 0.5 --omega-b 0.04 -o mf.txt > mf_log.txt 2>&1 ||
      { cat mf_log.txt; fail "mass-function"; }
    cat mf_log.txt
    "$python" - <<'EOT' || { cat mf.txt; fail "the mass-function table is wrong"; }
import h5py, numpy as np, sys
t = np.loadtxt('mf.txt')
mass = h5py.File('g1.hdf5', 'r')['Group/GroupMass'][:]
counts, _ = np.histogram(np.log10(mass), bins=np.arange(12.0, 14.51, 0.5))
ok = t.shape == (5, 5) and np.array_equal(t[:, 2], counts) and counts.sum() == 2
st = t[:, 4]
ok = ok and np.all(st > 0) and np.all(np.diff(st) < 0)
sys.exit(0 if ok else 1)
EOT
    set +e
    "$bin" mass-function g1.hdf5 --log-min 14 --log-max 13 -o mf.txt > bad.txt 2>&1; status=$?
    set -e
    [ "$status" -eq 2 ] && grep -q "log-max" bad.txt || { cat bad.txt; fail "an empty bin range was not refused"; } ;;
  hop_catalogue)
    # `fountain hop` on a snapshot's baryons: two Plummer clumps of gas (with hidden stellar
    # mass) and stars, 1 Mpc/h apart. Two groups at the paper's thresholds (80, 200 and 240
    # mean baryon densities), their masses counting the hidden stars, the same on 1 and 2
    # threads; a header without OmegaBaryon needs --omega-b.
    "$python" - <<'EOT'
import h5py, numpy as np
rng = np.random.default_rng(6)
def plummer(n, b, centre):
    r = b / np.sqrt(rng.random(3 * n) ** (-2.0 / 3.0) - 1.0)
    r = r[r < 20 * b][:n]
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None] * r[:, None] + centre
gas = np.concatenate([plummer(3000, 0.05, 4.0), plummer(2000, 0.05, 5.0)])
stars = np.concatenate([plummer(500, 0.03, 4.0), plummer(300, 0.03, 5.0)])
for name, omega_b in (('baryons.hdf5', 0.03), ('no_omega_b.hdf5', None)):
    with h5py.File(name, 'w') as f:
        h = f.create_group('Header')
        h.attrs['NumPart_ThisFile'] = np.array([len(gas), 0, 0, 0, len(stars), 0], dtype=np.uint64)
        h.attrs['MassTable'] = np.array([1e6, 0, 0, 0, 2e6, 0])
        h.attrs['BoxSize'] = 10.0
        h.attrs['Time'] = 0.5
        h.attrs['Omega0'] = 0.3
        h.attrs['OmegaLambda'] = 0.7
        h.attrs['HubbleParam'] = 0.6
        if omega_b is not None:
            h.attrs['OmegaBaryon'] = omega_b
        for t, x in ((0, gas), (4, stars)):
            g = f.create_group(f'PartType{t}')
            g['Coordinates'] = x
            g['Velocities'] = np.zeros_like(x)
            g['ParticleIDs'] = np.arange(1, len(x) + 1, dtype=np.uint64) + (0 if t == 0 else 100000)
        f['PartType0/HiddenStellarMasses'] = np.full(len(gas), 1e5)
EOT
    "$bin" hop baryons.hdf5 -o h1.hdf5 -t 1 > hop1.txt 2>&1 || { cat hop1.txt; fail "hop on 1 thread"; }
    "$bin" hop baryons.hdf5 -o h2.hdf5 -t 2 > hop2.txt 2>&1 || { cat hop2.txt; fail "hop on 2 threads"; }
    cat hop2.txt
    "$python" - <<'EOT' || fail "the HOP catalogue is wrong"
import h5py, numpy as np, sys
a, b = h5py.File('h1.hdf5', 'r'), h5py.File('h2.hdf5', 'r')
g = a['Group']
n_type = g['GroupLenType'][:]
m_type = g['GroupMassType'][:]
ok = a['Header'].attrs['Ngroups_Total'] == 2 and n_type[0, 0] > n_type[1, 0] > 500 and n_type[1, 4] > 100
# Gas 1e6 each plus 1e5 hidden, stars 2e6 each.
ok = ok and np.allclose(g['GroupMass'][:], 1.1e6 * n_type[:, 0] + 2e6 * n_type[:, 4], rtol=1e-12)
ok = ok and np.allclose(m_type[:, 4], 1e5 * n_type[:, 0] + 2e6 * n_type[:, 4], rtol=1e-12)
peaks = g['GroupPeakPos'][:]
ok = ok and np.abs(peaks[0] - 4.0).max() < 0.05 and np.abs(peaks[1] - 5.0).max() < 0.05
for name in ['Group/GroupLen', 'Group/GroupMass', 'IDs/ID', 'IDs/Density']:
    ok = ok and np.array_equal(a[name][:], b[name][:])
sys.exit(0 if ok else 1)
EOT
    set +e
    "$bin" hop no_omega_b.hdf5 -o h3.hdf5 > bad.txt 2>&1; status=$?
    set -e
    [ "$status" -eq 2 ] && grep -q "no_omega_b.hdf5.*give --omega-b" bad.txt || { cat bad.txt; fail "a missing Omega_b was not named"; }
    "$bin" hop no_omega_b.hdf5 -o h3.hdf5 --omega-b 0.03 > ok.txt 2>&1 || { cat ok.txt; fail "--omega-b was not taken"; } ;;
  ic_zoom)
    # The zoom pipeline at toy size (levels 3, 4, 5 in 20 Mpc/h): the parent run's initial
    # conditions, the parent run to z = 0, its halos, and zoom initial conditions on one of
    # them: gas and dark matter of level 5 in the traced region, level-4 and level-3 dark matter
    # (GADGET type 2) elsewhere, the box's whole matter content; they run. Bad options are named.
    cosmology="--box 20 --omega-b 0.03 --hubble 0.6 --seed 2"
    # shellcheck disable=SC2086
    "$bin" ic zoom --levels 3 4 5 $cosmology -o parent.hdf5 > ic.txt 2>&1 || { cat ic.txt; fail "parent ICs"; }
    grep -q "16^3 dark matter particles of 1.626e+11 Msun/h" ic.txt || { cat ic.txt; fail "parent ICs' summary"; }
    cat > parent.yml <<EOT
initial_conditions: {file: parent.hdf5, periodic: true}
cosmology: {enabled: true, omega_b: 0.03, hubble_param: 0.6, a_end: 1}
gravity: {enabled: true, softening_dark_matter: 0.044, mesh_cells: 32}
time_integration: {dt_max: 1}
output: {directory: parent_run}
EOT
    "$bin" run parent.yml -q > run.txt 2>&1 || { cat run.txt; fail "parent run"; }
    "$bin" fof parent_run/snapshot_0001.hdf5 -o fof.hdf5 --min-members 20 > fof.txt 2>&1 || { cat fof.txt; fail "fof"; }
    # shellcheck disable=SC2086
    "$bin" ic zoom --levels 3 4 5 $cosmology --parent parent_run/snapshot_0001.hdf5 --groups fof.hdf5 --halo 0 \
      --target 1000 -o zoom.hdf5 > zoom.txt 2>&1 || { cat zoom.txt; fail "zoom ICs"; }
    cat zoom.txt
    "$python" - <<'EOT' || fail "the zoom ICs are wrong"
import h5py, numpy as np, sys
f = h5py.File('zoom.hdf5', 'r')
n = f['Header'].attrs['NumPart_ThisFile']
m = sum(f[f'PartType{t}/Masses'][:].sum() for t in (0, 1, 2))
rho_crit = 3 * 100.0**2 / (8 * np.pi * 4.300917270069976e-09)
fine = f['PartType1/Masses'][:]
coarse = np.unique(f['PartType2/Masses'][:])
ok = n[0] == n[1] and n[0] >= 1000 and n[0] % 8 == 0 and n[2] > 0
ok = ok and abs(m / (0.3 * rho_crit * 20.0**3) - 1) < 1e-5
# Two coarse masses: a level-4 block is 8 level-5 cells, a level-3 block 64.
cell = fine[0] + f['PartType0/Masses'][0]
ok = ok and len(coarse) == 2 and np.allclose(coarse / cell, [8, 64], rtol=1e-12)
sys.exit(0 if ok else 1)
EOT
    # The paper's MFB/100: the same zoom at masses / 100, lengths and velocities x 100^(-1/3).
    # shellcheck disable=SC2086
    "$bin" ic zoom --levels 3 4 5 $cosmology --parent parent_run/snapshot_0001.hdf5 --groups fof.hdf5 --halo 0 \
      --target 1000 --mass-scale 0.01 -o small.hdf5 > small.txt 2>&1 || { cat small.txt; fail "scaled zoom ICs"; }
    "$python" - <<'EOT' || fail "the scaled zoom ICs are wrong"
import h5py, numpy as np, sys
a, b = h5py.File('zoom.hdf5', 'r'), h5py.File('small.hdf5', 'r')
s = 0.01 ** (1 / 3)
ok = abs(b['Header'].attrs['BoxSize'] / (20 * s) - 1) < 1e-12
for t in (0, 1, 2):
    ok = ok and np.allclose(b[f'PartType{t}/Masses'][:], 0.01 * a[f'PartType{t}/Masses'][:], rtol=1e-12)
    ok = ok and np.allclose(b[f'PartType{t}/Coordinates'][:], s * a[f'PartType{t}/Coordinates'][:], rtol=1e-12, atol=1e-12)
    ok = ok and np.allclose(b[f'PartType{t}/Velocities'][:], s * a[f'PartType{t}/Velocities'][:], rtol=1e-12, atol=1e-12)
ok = ok and np.allclose(b['PartType0/InternalEnergy'][:], s * s * a['PartType0/InternalEnergy'][:], rtol=1e-12)
sys.exit(0 if ok else 1)
EOT
    sed 's/parent.hdf5/zoom.hdf5/; s/parent_run/zoom_run/; s/a_end: 1/a_end: 0.03/' parent.yml > zoom.yml
    printf 'hydro: {h_max: 2.0}
' >> zoom.yml
    "$bin" run zoom.yml -q > zrun.txt 2>&1 || { cat zrun.txt; fail "zoom run"; }
    # shellcheck disable=SC2086
    expect_status_message() {  # expect_status_message MESSAGE COMMAND...
      message=$1; shift
      set +e
      "$@" > bad.txt 2>&1; status=$?
      set -e
      [ "$status" -eq 2 ] && grep -q -- "$message" bad.txt || { cat bad.txt; fail "not refused: $*"; }
    }
    expect_status_message "coarsest = parent or parent - 1" "$bin" ic zoom --levels 2 4 5 -o bad.hdf5
    expect_status_message "go together" "$bin" ic zoom --levels 3 4 5 --parent parent_run/snapshot_0001.hdf5 -o bad.hdf5
    expect_status_message "does not apply to zoom" "$bin" ic zoom -n 16 -o bad.hdf5
    expect_status_message "applies to zoom only" "$bin" ic cosmo --levels 3 4 5 -o bad.hdf5
    expect_status_message "fix-amplitudes does not apply to zoom" "$bin" ic zoom --levels 3 4 5 --fix-amplitudes -o bad.hdf5
    expect_status_message "has 2 groups\|has [0-9]* groups" "$bin" ic zoom --levels 3 4 5 --box 20 --omega-b 0.03 \
      --hubble 0.6 --parent parent_run/snapshot_0001.hdf5 --groups fof.hdf5 --halo 999 -o bad.hdf5 ;;
  ic_cosmo_run)
    # Fountain's own cosmological box (2 x 8^3, 2LPT, z = 49) runs comovingly with the
    # cosmology it was made for, and refuses another; bad options are named.
    "$bin" ic cosmo -n 8 --box 20 --omega-b 0.03 --hubble 0.6 --seed 5 -o box.hdf5 > ic.txt 2>&1 || { cat ic.txt; fail "ic cosmo"; }
    grep -q "^wrote box.hdf5 (8^3 dark matter and gas particles" ic.txt || { cat ic.txt; fail "ic cosmo's summary"; }
    # The file says how it was made; its paired partner says so too, and its dark matter moves
    # the other way (the Zel'dovich and 2LPT parts: x_A + x_B - 2q is second order alone).
    "$bin" ic cosmo -n 8 --box 20 --omega-b 0.03 --hubble 0.6 --seed 5 --invert-phases -o partner.hdf5 > ic2.txt 2>&1 \
      || { cat ic2.txt; fail "ic cosmo --invert-phases"; }
    "$python" - <<'EOT' || fail "the /Cosmology records or the partner's field are wrong"
import h5py, numpy as np, sys
a, b = h5py.File('box.hdf5', 'r'), h5py.File('partner.hdf5', 'r')
ca, cb = a['Cosmology'].attrs, b['Cosmology'].attrs
ok = ca['Seed'] == b'5' and cb['Seed'] == b'5' and ca['InvertPhases'] == 0 and cb['InvertPhases'] == 1
ok = ok and ca['Generator'] == b'fountain ic cosmo' and ca['Level'] == 3 and ca['LPTOrder'] == 2 and ca['Sigma8'] == 0.9
cell = 20.0 / 8
ia, ib = np.argsort(a['PartType1/ParticleIDs'][:]), np.argsort(b['PartType1/ParticleIDs'][:])
ids = a['PartType1/ParticleIDs'][:][ia] - 1  # ID 1 + n for lattice cell n = (i N + j) N + k
lattice = np.stack([ids // 64 + 0.5, (ids // 8) % 8 + 0.5, ids % 8 + 0.5], axis=1) * cell
da = a['PartType1/Coordinates'][:][ia] - lattice
db = b['PartType1/Coordinates'][:][ib] - lattice
da -= 20.0 * np.round(da / 20.0)
db -= 20.0 * np.round(db / 20.0)
first = np.abs(da - db).max() / 2   # the first-order part, reversed
second = np.abs(da + db).max() / 2  # the second-order part, kept
ok = ok and first > 0.01 * cell and second < 0.1 * first
print(f"partner: first-order displacement up to {first:.3g}, second-order {second:.3g} Mpc/h")
sys.exit(0 if ok else 1)
EOT
    cat > params.yml <<EOT
initial_conditions:
  file: box.hdf5
  periodic: true
cosmology:
  enabled: true
  omega_b: 0.03
  hubble_param: 0.6
  a_end: 0.04
gravity:
  enabled: true
  softening_dark_matter: 0.1
time_integration:
  dt_max: 1
output:
  directory: out
EOT
    "$bin" run params.yml -q > run.txt 2>&1 || { cat run.txt; fail "comoving run of ic cosmo's box"; }
    grep -q "^done: .* steps to a = 0.04" run.txt || { cat run.txt; fail "the run did not reach a = 0.04"; }
    "$python" "$root/tests/check_snapshot_yt.py" out/snapshot_0001.hdf5
    sed -i 's/hubble_param: 0.6/hubble_param: 0.7/; s/directory: out/directory: out2/' params.yml
    expect_error "HubbleParam = 0.6 differs from params.yml:.*cosmology.hubble_param.* = 0.7"
    set +e
    "$bin" ic cosmo -n 12 -o bad.hdf5 > bad.txt 2>&1; status=$?
    set -e
    [ "$status" -eq 2 ] && grep -q "power of two" bad.txt || { cat bad.txt; fail "-n 12 was not refused"; }
    set +e
    "$bin" ic sod --box 3 -o bad.hdf5 > bad.txt 2>&1; status=$?
    set -e
    [ "$status" -eq 2 ] && grep -q "applies to cosmo and zoom only" bad.txt || { cat bad.txt; fail "--box for sod was not refused"; } ;;
  snapshot_opens_in_yt)
    params good.hdf5 out
    "$bin" run params.yml -q > out.txt 2>&1 || { cat out.txt; fail "run failed"; }
    "$python" "$root/tests/check_snapshot_yt.py" out/snapshot_0001.hdf5 ;;
  threads_bitwise)
    T_END=0.01 params good.hdf5 out1; "$bin" run params.yml -q -t 1 > /dev/null 2>&1 || fail "1-thread run"
    T_END=0.01 params good.hdf5 out2; "$bin" run params.yml -q -t 2 > /dev/null 2>&1 || fail "2-thread run"
    T_END=0.01 params good.hdf5 out3; "$bin" run params.yml -q -t 2 > /dev/null 2>&1 || fail "repeat run"
    "$python" "$root/tests/compare_snapshots.py" out1/snapshot_0001.hdf5 out2/snapshot_0001.hdf5
    "$python" "$root/tests/compare_snapshots.py" out2/snapshot_0001.hdf5 out3/snapshot_0001.hdf5 ;;
  sigterm_stops_with_restart)
    # SIGTERM: a restart file, then exit status 75 (EX_TEMPFAIL: "continue with --restart"),
    # so scripts can tell a stopped run from a finished one; the restart then finishes it.
    # Timing a kill against a run of a few milliseconds is a race, so the signal is made
    # certain instead: the launcher blocks SIGTERM, raises it (pending across exec) and execs
    # fountain, which must take it as soon as its handler is in place and stop after step 1.
    T_END=0.03 params good.hdf5 out
    set +e
    "$python" -c 'import os, signal, sys
signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGTERM])
os.kill(os.getpid(), signal.SIGTERM)
os.execv(sys.argv[1], sys.argv[1:])' "$bin" run params.yml > run.txt 2>&1
    status=$?
    set -e
    grep -q "stopped by SIGTERM at step 1;" run.txt || { cat run.txt; fail "the run was not stopped by SIGTERM after step 1 (status $status)"; }
    [ "$status" -eq 75 ] || { cat run.txt; fail "exit status $status after SIGTERM, expected 75"; }
    [ -f out/restart.hdf5 ] || fail "no restart file after SIGTERM"
    "$bin" run params.yml -q --restart > restart.txt 2>&1 || { cat restart.txt; fail "restart after SIGTERM"; }
    grep -q "^done" restart.txt || { cat restart.txt; fail "the restarted run did not finish"; }
    echo "ok: $(grep 'stopped by SIGTERM' run.txt)" ;;
  restart_after_kill)
    # The same run uninterrupted (A), and stopped half-way as a kill would stop it then
    # restarted (B), must end with bitwise-identical snapshots. Both write restart files
    # every 4 steps.
    extra="restart:
  every_steps: 4"
    T_END=0.03 params good.hdf5 outA "$extra"; cp params.yml paramsA.yml
    T_END=0.03 params good.hdf5 outB "$extra"; cp params.yml paramsB.yml
    "$bin" run paramsA.yml > runA.txt 2>&1 || { cat runA.txt; fail "uninterrupted run"; }
    # (The gravity variants below send a real SIGKILL, to runs long enough to be caught.)
    stop_half_way "$(grep -c '^step' runA.txt)" "$bin" run paramsB.yml
    "$bin" run paramsB.yml --restart > restart.txt 2>&1 || { cat restart.txt; fail "restart failed"; }
    head -1 restart.txt
    "$python" "$root/tests/compare_snapshots.py" outA/snapshot_0001.hdf5 outB/snapshot_0001.hdf5 ;;
  restart_after_kill_gravity|restart_after_kill_star_formation)
    # As restart_after_kill, with everything a restart must carry beyond the gas: a rotating
    # sphere of gas and dark matter, self-gravity (open boundaries), cooling and MSPH, on
    # individual timesteps (the collapse spreads the particles over several bins). B writes
    # restart files every 25 steps and A none (a restart file is written at a recut the run
    # makes anyway, so writing one changes nothing); B is killed with SIGKILL after one
    # written at step 100 or later, and restarted.
    # The star formation variant runs on into the disc's star formation with MFB on: hidden
    # stars, reservoirs, promotions, star particles and the tallies must all come back.
    "$bin" ic sphere -n 300 -o sphere.hdf5 > /dev/null 2>&1 || fail "cannot write the sphere ICs"
    t_end=4e-4 extra="" kill_after='[1-9][0-9][0-9]+'
    if [ "$case_name" = restart_after_kill_star_formation ]; then
      t_end=6e-4 kill_after='1[0-9][0-9][0-9]'  # step 1000-1999: stars, reservoirs, promotions exist
      extra="$sphere_feedback"
    fi
    gparams() {  # gparams OUT_DIR [RESTART_YAML]
      cat > params.yml <<EOT
$extra
run:
  t_end: $t_end
initial_conditions:
  file: sphere.hdf5
  periodic: false
output:
  directory: $1
time_integration:
  dt_max: 1e-5
  dt_min: 1e-14
$sphere_physics
${2:-}
EOT
    }
    gparams outA; cp params.yml paramsA.yml
    gparams outB "restart:
  every_steps: 25"; cp params.yml paramsB.yml
    "$bin" run paramsA.yml > runA.txt 2>&1 || { cat runA.txt; fail "uninterrupted run"; }
    total=$(grep -c '^step' runA.txt)
    "$bin" run paramsB.yml > runB.txt 2>&1 &
    pid=$!
    n=0
    until grep -Eq "restart file .* at step ($kill_after)\$" runB.txt || ! kill -0 "$pid" 2>/dev/null || [ $n -ge 3000 ]; do
      sleep 0.01; n=$((n + 1))
    done
    kill -9 "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
    [ -f outB/restart.hdf5 ] || { cat runB.txt; fail "no restart file was written"; }
    [ ! -f outB/snapshot_0001.hdf5 ] || fail "the run ended before it was killed"
    echo "killed after $(grep -c '^step' runB.txt) of $total steps; $(grep 'restart file' runB.txt | tail -1)"
    "$bin" run paramsB.yml --restart > restart.txt 2>&1 || { cat restart.txt; fail "restart failed"; }
    head -1 restart.txt
    "$python" -c "
import h5py, sys
with h5py.File('outA/snapshot_0001.hdf5', 'r') as f:
    sys.exit(0 if f['PartType1/Coordinates'].shape[0] > 0 else 1)" || fail "no dark matter in the snapshot"
    if [ "$case_name" = restart_after_kill_star_formation ]; then
      "$python" -c "
import h5py, sys
with h5py.File('outA/snapshot_0001.hdf5', 'r') as f:
    sys.exit(0 if f['Header'].attrs['NumPart_ThisFile'][4] > 0 and f['PartType0/Promoted'][:].sum() > 0 else 1)" ||
        fail "the run formed no star particle or promoted nothing: the test would prove little"
    fi
    "$python" "$root/tests/compare_snapshots.py" outA/snapshot_0001.hdf5 outB/snapshot_0001.hdf5 ;;
  corrupted_restart)
    # Long enough for the cells to be recut after a few steps: restart files are written at
    # recuts.
    T_END=0.03 params good.hdf5 out "restart:
  every_steps: 1"
    "$bin" run params.yml -q > /dev/null 2>&1 || fail "run"
    "$python" -c "
import h5py
with h5py.File('out/restart.hdf5', 'a') as f: f['Gas/u'][2] = 1.2345"
    expect_error_restart() {
      set +e; "$bin" run params.yml -q --restart > out.txt 2>&1; status=$?; set -e
      [ "$status" -eq 2 ] || { cat out.txt; fail "exit status $status, expected 2"; }
      grep -q -- "$1" out.txt || { cat out.txt; fail "message does not mention '$1'"; }
      echo "ok: $(cat out.txt)"
    }
    expect_error_restart "corrupted"
    # A run folder moved elsewhere continues from its restart file (output.directory may
    # change), and may turn on timeline dumps (diagnostics only) and pinned threads.
    "$bin" run params.yml -q --overwrite > /dev/null 2>&1 || fail "run"
    cp -r out moved
    sed 's/^  directory: out$/  directory: moved\n  dump_timeline_every: 1/; s/^run:$/run:\n  pin_threads: true/' \
      params.yml > moved.yml
    grep -q "dump_timeline_every: 1" moved.yml || fail "test set-up: no timeline key"
    grep -q "pin_threads: true" moved.yml || fail "test set-up: no pinning key"
    "$bin" run moved.yml -q --restart > moved.txt 2>&1 || { cat moved.txt; fail "restart of a moved run folder"; }
    ls moved/timeline_step*.csv > /dev/null || fail "no timeline after the restart"
    # A restart file of another problem (other parameters) is refused too.
    sed -i 's/^  t_end: .*/  t_end: 0.5/' params.yml
    expect_error_restart "run.t_end" ;;
  task_dumps)
    params good.hdf5 out "output:
  directory: out
  dump_task_graph: true
  dump_timeline_every: 1"
    sed -i '0,/^output:$/{/^output:$/d};0,/^  directory: out$/{/^  directory: out$/d}' params.yml
    "$bin" run params.yml -q > out.txt 2>&1 || { cat out.txt; fail "run failed"; }
    [ -s out/task_graph.dot ] || fail "no DOT graph"
    head -2 out/dependency_graph_0.csv | grep -q "task_in,task_out" || fail "no SWIFT-style CSV"
    ls out/timeline_step*.csv > /dev/null || fail "no timeline"
    "$python" "$root/tasks/plot_tasks.py" out/timeline_step000001.csv -o gantt.png > summary.txt || fail "plot tool"
    [ -s gantt.png ] || fail "no Gantt PNG"
    grep -q density summary.txt || fail "summary lacks density" ;;
  *) fail "unknown case $case_name" ;;
esac
echo "PASS: $case_name"
