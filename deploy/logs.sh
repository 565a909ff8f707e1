#!/usr/bin/env bash
# Follows the coordinator's log of the cluster deploy/up.sh started, from any shell: the settings
# (token, config, results folder) come from ~/.local/state/amorph/<project>.env, which up.sh
# wrote (AMORPH_PROJECT, default amorph, names the cluster).
#   deploy/logs.sh [compose logs options]     e.g. deploy/logs.sh --tail 20
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
env_file="${XDG_STATE_HOME:-$HOME/.local/state}/amorph/${AMORPH_PROJECT:-amorph}.env"
[ -f "$env_file" ] || { echo "logs.sh: $env_file not found: start the cluster with deploy/up.sh" >&2; exit 2; }
set -a
# shellcheck source=/dev/null
. "$env_file"
set +a
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(-f)
exec "$root/deploy/compose.sh" -p "$AMORPH_PROJECT" -f "$root/deploy/docker-compose.yml" \
  logs "${args[@]}" coordinator
