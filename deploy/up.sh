#!/usr/bin/env bash
# Builds the images (offline, from this machine's binaries) and starts the local cluster on a config:
#   deploy/up.sh CONFIG [WORKERS]        e.g. deploy/up.sh configs/quickstart.toml 2
# Results land in ./results/<name>/ (AMORPH_RESULTS to change); the token is made up unless
# AMORPH_TOKEN is set. Follow with: deploy/compose.sh -p amorph -f deploy/docker-compose.yml logs -f
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
"$root/deploy/stage.sh" "${AMORPH_PROFILE:-release}"
"$root/deploy/compose.sh" -p "${AMORPH_PROJECT:-amorph}" -f "$root/deploy/docker-compose.yml" \
  up --build -d --scale "worker=$workers"
echo "cluster up: $workers workers on $(basename "$config"); results in $AMORPH_RESULTS"
echo "follow:  deploy/compose.sh -p ${AMORPH_PROJECT:-amorph} -f deploy/docker-compose.yml logs -f coordinator"
echo "stop:    deploy/down.sh   (results are kept)"
