#!/usr/bin/env bash
# Fault tests of the docker-compose cluster, run by .ci/run. Each scenario brings up one
# coordinator and two worker containers on a short beam run, breaks something mid-run, and checks
# that the final population is byte-identical to the same run done in one process on the host:
#   plain      nothing breaks (by name only: each fault scenario below checks the same and more)
#   kill       one worker container is killed (docker kill)
#   partition  one worker is cut off the network, then reconnected (leases expire, it rejoins)
#   restart    the coordinator container is restarted (it resumes from its run store)
# Every container and network is removed on exit, also when a scenario fails.
#
#   deploy/fault-tests.sh [scenario...]     (default: kill partition restart; AMORPH_PROFILE=release for release binaries)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
compose() { "$root/deploy/compose.sh" -f "$root/deploy/docker-compose.yml" "$@"; }
profile="${AMORPH_PROFILE:-debug}"
scenarios=("$@")
[ ${#scenarios[@]} -gt 0 ] || scenarios=(kill partition restart)

work="$(mktemp -d /tmp/amorph-fault.XXXXXX)"
export AMORPH_TOKEN="fault-$$" AMORPH_UID="$(id -u)" AMORPH_GID="$(id -g)"
export AMORPH_CONFIG="$work/run.toml"
projects=()
cleanup() {
  local status=$?
  for p in "${projects[@]}"; do
    AMORPH_RESULTS=/tmp compose -p "$p" down --remove-orphans --timeout 1 >/dev/null 2>&1 || true
  done
  if [ $status -eq 0 ]; then rm -rf "$work"; else echo "fault-tests: FAILED (work folder kept: $work)" >&2; fi
}
trap cleanup EXIT
log() { echo "fault-tests: $*"; }

# A beam run long enough to break things in the middle (~0.1 s per evaluation, 2 workers): the
# test fixture, copied where the containers mount it (/config/run.toml).
cp "$root/tests/fixtures/configs/fault_beam.toml" "$AMORPH_CONFIG"
budget="$(sed -n 's/^evaluations = //p' "$AMORPH_CONFIG")"

"$root/deploy/stage.sh" "$profile" >/dev/null
AMORPH_RESULTS=/tmp compose -p amorphft build >/dev/null 2>&1 || AMORPH_RESULTS=/tmp compose -p amorphft build
log "images built ($profile binaries)"

mkdir -p "$work/reference"
start=$(date +%s)
(cd "$work/reference" && "$root/target/$profile/coordinator" --config "$AMORPH_CONFIG" --local-workers 2 >/dev/null 2>"$work/reference/log")
reference="$work/reference/results/ft/population.json"
log "reference run in one process: $(( $(date +%s) - start )) s"

evaluations() {
  python3 - "$1" <<'PY'
import sqlite3, sys
try:
    print(sqlite3.connect(sys.argv[1], timeout=5).execute("select count(*) from evaluation").fetchone()[0])
except Exception:
    print(0)
PY
}

wait_for_evaluations() { # store count timeout
  local deadline=$(( $(date +%s) + $3 ))
  until [ "$(evaluations "$1")" -ge "$2" ]; do
    [ "$(date +%s)" -lt "$deadline" ] || { echo "fewer than $2 evaluations after $3 s" >&2; return 1; }
    sleep 0.2
  done
}

run_scenario() {
  runs=$(( ${runs:-0} + 1 ))
  local name="$1" project="amorphft${1}${runs}x$$" dir="$work/$1-$runs"
  projects+=("$project")
  mkdir -p "$dir/results"
  export AMORPH_RESULTS="$dir/results"
  local start; start=$(date +%s)
  compose -p "$project" up -d --scale worker=2 >/dev/null 2>&1
  local coordinator workers store="$dir/results/ft/run.sqlite"
  coordinator="$(compose -p "$project" ps -q coordinator)"
  mapfile -t workers < <(compose -p "$project" ps -q worker)
  [ ${#workers[@]} -eq 2 ] || { echo "$name: expected 2 workers, got ${#workers[@]}" >&2; return 1; }
  case "$name" in
    plain) ;;
    kill)
      wait_for_evaluations "$store" 60 180
      docker kill "${workers[0]}" >/dev/null
      ;;
    partition)
      wait_for_evaluations "$store" 60 180
      local net="${project}_default"
      docker network disconnect -f "$net" "${workers[0]}"
      sleep 4 # longer than the lease (2 s) and the worker timeout (1 s)
      docker network connect "$net" "${workers[0]}"
      ;;
    restart)
      wait_for_evaluations "$store" 60 180
      docker restart -t 5 "$coordinator" >/dev/null
      ;;
    *) echo "unknown scenario $name" >&2; return 2 ;;
  esac
  local code; code="$(timeout 600 docker wait "$coordinator")"
  if [ "$code" != 0 ]; then
    compose -p "$project" logs --tail 30 >&2
    echo "$name: coordinator exited with $code" >&2
    return 1
  fi
  if ! cmp -s "$reference" "$dir/results/ft/population.json"; then
    echo "$name: final population differs from the in-process run" >&2
    return 1
  fi
  local stored; stored="$(evaluations "$store")"
  [ "$stored" -eq "$budget" ] || { echo "$name: $stored evaluations stored, expected $budget" >&2; return 1; }
  compose -p "$project" down --remove-orphans --timeout 1 >/dev/null 2>&1
  log "$name: bit-identical, $budget evaluations stored, $(( $(date +%s) - start )) s"
}

for s in "${scenarios[@]}"; do run_scenario "$s"; done

# The documented cluster commands: deploy/up.sh, then deploy/logs.sh and deploy/down.sh from a new
# shell with nothing exported, which read the settings up.sh kept.
up_project="amorphftup$$"
projects+=("$up_project")
mkdir -p "$work/up/results" "$work/up/state"
AMORPH_RESULTS="$work/up/results" AMORPH_PROJECT="$up_project" AMORPH_PROFILE="$profile" \
  XDG_STATE_HOME="$work/up/state" "$root/deploy/up.sh" "$AMORPH_CONFIG" 1 >/dev/null 2>&1
fresh_shell() { env -i PATH="$PATH" HOME="$HOME" XDG_STATE_HOME="$work/up/state" AMORPH_PROJECT="$up_project" "$@"; }
fresh_shell "$root/deploy/logs.sh" --tail 5 >/dev/null
fresh_shell "$root/deploy/down.sh" >/dev/null 2>&1
log "up.sh, then logs.sh and down.sh from a new shell"
log "all passed: ${scenarios[*]}, up/logs/down"
