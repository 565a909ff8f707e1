#!/usr/bin/env bash
# Builds the images (offline, from this machine's binaries) and starts the local cluster on a config:
#   deploy/up.sh CONFIG [WORKERS]        e.g. deploy/up.sh configs/quickstart.toml 2
# Results land in ./results/<name>/ (AMORPH_RESULTS to change); the token is made up unless
# AMORPH_TOKEN is set. The cluster's settings are kept in ~/.local/state/amorph/<project>.env
# (readable by you alone), so that deploy/logs.sh and deploy/down.sh work from any new shell.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
config="${1:?usage: deploy/up.sh CONFIG [WORKERS]}"
workers="${2:-2}"
[ -f "$config" ] || { echo "up.sh: config $config does not exist" >&2; exit 2; }
export AMORPH_CONFIG="$(cd "$(dirname "$config")" && pwd)/$(basename "$config")"
export AMORPH_RESULTS="${AMORPH_RESULTS:-$root/results}"
export AMORPH_TOKEN="${AMORPH_TOKEN:-$(head -c 18 /dev/urandom | base64 | tr -d '/+=')}"
export AMORPH_UID="${AMORPH_UID:-$(id -u)}" AMORPH_GID="${AMORPH_GID:-$(id -g)}"
mkdir -p "$AMORPH_RESULTS"
export AMORPH_PROJECT="${AMORPH_PROJECT:-amorph}"
state="${XDG_STATE_HOME:-$HOME/.local/state}/amorph"
mkdir -p "$state"
env_file="$state/$AMORPH_PROJECT.env"
( umask 077
  for v in AMORPH_CONFIG AMORPH_RESULTS AMORPH_TOKEN AMORPH_UID AMORPH_GID AMORPH_PROJECT; do
    printf '%s=%q\n' "$v" "${!v}"
  done ) > "$env_file"
"$root/deploy/stage.sh" "${AMORPH_PROFILE:-release}"
"$root/deploy/compose.sh" -p "${AMORPH_PROJECT:-amorph}" -f "$root/deploy/docker-compose.yml" \
  up --build -d --scale "worker=$workers"
echo "cluster up: $workers workers on $(basename "$config"); results in $AMORPH_RESULTS"
echo "follow:  deploy/logs.sh   (from any shell)"
echo "stop:    deploy/down.sh   (results are kept)"
