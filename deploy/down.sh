#!/usr/bin/env bash
# Stops the local cluster and removes its containers and network; the results folder (a bind mount)
# is kept.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
# Compose checks these are set even to tear down.
export AMORPH_CONFIG="${AMORPH_CONFIG:-/dev/null}" AMORPH_TOKEN="${AMORPH_TOKEN:-x}"
"$root/deploy/compose.sh" -p "${AMORPH_PROJECT:-amorph}" -f "$root/deploy/docker-compose.yml" \
  down --remove-orphans --timeout 10
