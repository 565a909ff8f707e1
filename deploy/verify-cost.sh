#!/usr/bin/env bash
# What verification costs (docs/how-to/cluster.md): runs a config with the coordinator's own workers
# off and two outside `worker --connect` processes of one thread each, with `[cluster] verify` on or
# off, and prints the wall time, evaluations and checks its run store holds.
#
#   deploy/verify-cost.sh <config.toml> <out> <label> <true|false> <port> [evaluations] [shared|credentials]
#
# shared (the default): both workers hold one shared token, so they are one principal and the
# coordinator checks their claims itself; credentials: each holds a credential of its own, so they
# check each other.
# The config's wall-time limit is dropped (so both settings run the same evaluations) and its
# evaluation budget replaced when given. COORDINATOR and WORKER override the binaries (default
# target/release/*). Compare two runs' results with `cmp <out>/<a>/population.json <out>/<b>/...`.
set -euo pipefail
[[ $# -ge 5 ]] || { sed -n '5p' "$0" | sed 's/^# *//' >&2; exit 2; }
config=$1 out=$2 label=$3 verify=$4 port=$5 evaluations=${6:-} principals=${7:-shared}
coordinator=${COORDINATOR:-target/release/coordinator}
worker=${WORKER:-target/release/worker}
mkdir -p "$out"
out=$(cd "$out" && pwd)
file=$out/$label.toml
{
    echo "name = \"$label\""
    echo "results_dir = \"$out\""
    grep -Ev '^(name|results_dir|wall_seconds)[[:space:]]*=' "$config" |
        if [[ -n $evaluations ]]; then
            sed -E "s/^evaluations[[:space:]]*=.*/evaluations = $evaluations/"
        else
            cat
        fi
    echo "[cluster]"
    echo "local_workers = 0"
    echo "verify = $verify"
    if [[ $principals == credentials ]]; then
        echo "credentials_file = \"$out/$label.credentials\""
    fi
} >"$file"
rm -f "$out/$label.credentials" "$out/$label".*.token
export AMORPH_TOKEN=shared-$RANDOM$RANDOM$RANDOM
for name in outside-a outside-b; do
    if [[ $principals == credentials ]]; then
        "$coordinator" credentials add "$name" --file "$out/$label.credentials" \
            --token-out "$out/$label.$name.token" >/dev/null
    else
        (umask 077 && echo "$AMORPH_TOKEN" >"$out/$label.$name.token")
    fi
done
start=$(date +%s.%N)
"$coordinator" --config "$file" --listen "127.0.0.1:$port" --fresh >"$out/$label.log" 2>&1 &
pid=$!
for name in outside-a outside-b; do
    env -u AMORPH_TOKEN "$worker" --connect "http://127.0.0.1:$port" --threads 1 --name "$name" \
        --give-up-after 60 --token-file "$out/$label.$name.token" >"$out/$label.$name.log" 2>&1 &
done
wait "$pid"
wait
echo "$label: wall $(echo "$(date +%s.%N) - $start" | bc) s"
python3 - "$out/$label/run.sqlite" <<'PY'
import sqlite3, sys
c = sqlite3.connect(f"file:{sys.argv[1]}?mode=ro", uri=True)
one = lambda q: c.execute(q).fetchone()[0]
evaluations = one("select count(*) from evaluation")
checks = one("select count(*) from verification")
by_coordinator = one("select count(*) from verification where checker like '%coordinator'")
disagreements = one("select count(*) from verification where not agreed")
print(f"evaluations {evaluations}, checks {checks} ({100 * checks / max(evaluations, 1):.1f} %), "
      f"by the coordinator {by_coordinator}, disagreements {disagreements}")
PY
