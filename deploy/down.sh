#!/usr/bin/env bash
# Stops the local cluster and removes its containers and network; the results folder (a bind mount)
# is kept.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
env_file="${XDG_STATE_HOME:-$HOME/.local/state}/amorph/${AMORPH_PROJECT:-amorph}.env"
if [ -f "$env_file" ]; then set -a; . "$env_file"; set +a; fi
# Compose checks these are set even to tear down.
export AMORPH_CONFIG="${AMORPH_CONFIG:-/dev/null}" AMORPH_TOKEN="${AMORPH_TOKEN:-x}"
"$root/deploy/compose.sh" -p "${AMORPH_PROJECT:-amorph}" -f "$root/deploy/docker-compose.yml" \
  down --remove-orphans --timeout 10
