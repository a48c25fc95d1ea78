#!/bin/sh
# The layers' include rules, checked over every source file: a layer includes only layers below
# it. Physics (hydro, gravity, cooling, star formation, feedback, time integration) includes
# neither the engine nor the app, and feedback nothing of star formation; the step's context and
# clock (src/step) include no physics; the task machinery (tasks/) includes no physics, io,
# engine or app; io/ and domain/ nothing of the engine or the app; space, particles and core no
# layer above them; the group finders (src/groups) nothing of a run. Usage: check_layers.sh REPO_ROOT
set -eu
root=${1:?repo root}
cd "$root"
status=0
# rule FOLDER FORBIDDEN_INCLUDE_PREFIXES...
rule() {
  folder=$1; shift
  [ -d "$folder" ] || return 0
  for prefix in "$@"; do
    hits=$(grep -rn --include='*.hpp' --include='*.cpp' "^#include \"$prefix/" "$folder" || true)
    if [ -n "$hits" ]; then
      echo "FAIL: $folder must not include $prefix/:"
      echo "$hits"
      status=1
    fi
  done
}
physics="hydro gravity cooling star_formation feedback timestep"
for layer in $physics; do rule "src/$layer" engine app; done
# Star formation calls feedback (what forms deposits its energy); feedback never star formation.
rule src/feedback star_formation
rule src/domain engine app
# shellcheck disable=SC2086
rule src/step $physics engine app io analysis ics domain
# shellcheck disable=SC2086
rule tasks $physics step engine app io space particles analysis ics domain params
rule io engine app
# shellcheck disable=SC2086
for layer in space particles core; do rule "src/$layer" $physics step engine app io analysis ics domain; done
# The group finders work on particle sets, not on a run: no engine, app, io or step.
rule src/groups engine app io step hydro cooling star_formation feedback timestep domain
# The expanding background is a function of a alone: it sits with core, below everything.
# shellcheck disable=SC2086
rule src/cosmology $physics step engine app io analysis ics domain space particles
[ "$status" -eq 0 ] && echo "PASS: every include follows the layers"
exit "$status"
