#!/usr/bin/env bash
# `docker compose` where the plugin exists, else the standalone docker-compose.
if docker compose version >/dev/null 2>&1; then exec docker compose "$@"; fi
exec docker-compose "$@"
