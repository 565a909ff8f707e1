#!/usr/bin/env bash
# Study: does the discontinuous slope reach half the paper's error (0.43 %) within 20,000
# evaluations on more seeds with four islands of 12 than with the shipped one island of 50?
#
# Runs (fixed before any was made): the shipped config (`configs/discontinuous_slope.toml`) at
# seeds 104 and 105 (seeds 101-103 were measured on 2026-12-06 with a build of the same bits:
# 0.3998 % reached, 0.6267 % and 0.4756 % not), and the same config with
# `search.islands=4 search.population=12 search.children_per_epoch=12` at seeds 101-105.
# Rule: islands become the slope config's search if they reach 0.43 % on at least 4 of 5 seeds
# and on at least 2 more seeds than the shipped config, else the question is closed as lost.
# Each run: release binary, 2 local workers, one run at a time. Prints one line per run.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=target/release/coordinator
run() { # arm seed extra-sets...
  local arm=$1 seed=$2; shift 2
  local name="study_slope_${arm}_${seed}"
  rm -rf "results/$name"
  local start=$SECONDS
  nice -n 5 "$bin" --config configs/discontinuous_slope.toml --set "name=\"$name\"" --set "seed=$seed" "$@" > "/tmp/$name.out" 2>&1
  python3 - "$arm" "$seed" "results/$name/summary.json" $((SECONDS - start)) <<'PY'
import json, sys
arm, seed, path, secs = sys.argv[1:]
s = json.load(open(path))
def find(d, keys):
    for k, v in d.items():
        if k in keys: return v
        if isinstance(v, dict):
            r = find(v, keys)
            if r is not None: return r
    return None
print(arm, seed, find(s, {"best_rms_percent", "rms_percent"}), find(s, {"evaluations"}), find(s, {"stop"}), f"{secs}s", flush=True)
PY
}
islands=(--set search.islands=4 --set search.population=12 --set search.children_per_epoch=12)
for step in "islands 101" "shipped 104" "islands 102" "shipped 105" "islands 103" "islands 104" "islands 105"; do
  set -- $step
  if [ "$1" = islands ]; then run islands "$2" "${islands[@]}"; else run shipped "$2"; fi
done
