#!/usr/bin/env bash
# Checks the cluster recipes beyond one machine, as far as this machine allows (run by .ci/run):
# - the Kubernetes manifests validate against the Kubernetes API schemas (kubernetes-validate from
#   PyPI, installed into a virtualenv under target/), and a broken manifest is caught;
# - the shell scripts, including the Slurm batch script, parse; study.sh --set edits a config,
#   study.sh resume finishes the runs a stop cut short, and study.sh summary ranks settings.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
venv="$root/target/recipes-venv"
if [ ! -x "$venv/bin/kubernetes-validate" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check kubernetes-validate
fi
"$venv/bin/kubernetes-validate" --strict --quiet deploy/k8s/*.yaml
# The validator must be able to fail: a replica count that is not a number.
broken="$(mktemp)"
trap 'rm -f "$broken"' EXIT
sed 's/replicas: 4/replicas: four/' deploy/k8s/workers.yaml > "$broken"
if "$venv/bin/kubernetes-validate" --strict --quiet "$broken" >/dev/null 2>&1; then
  echo "check-recipes: the validator accepted a broken manifest" >&2
  exit 1
fi
for script in deploy/*.sh deploy/slurm/amorph.sbatch; do bash -n "$script"; done
# study.sh --set (the docs' study commands rely on it): each value lands in its own section, a
# missing section is added, the rest of the config is kept, and a malformed --set stops the study.
study="$(mktemp -d)"
trap 'rm -f "$broken"; rm -rf "$study"' EXIT
printf '#!/bin/sh\ncp "$2" "%s/seen.toml"\n' "$study" > "$study/coordinator"
chmod +x "$study/coordinator"
COORDINATOR="$study/coordinator" deploy/study.sh run "$study/out" configs/circular_arc_finest4.toml \
  --set scene.target=straight --set search.islands=16 --set search.migration.interval=7 \
  --target 0.10 --label set 3 2>/dev/null
python3 - "$study/seen.toml" <<'EOF'
import sys, tomllib
c = tomllib.load(open(sys.argv[1], "rb"))
s = c.get("search", {})
got = (c.get("name"), c.get("seed"), c.get("scene", {}).get("target"), s.get("islands"),
       s.get("children_per_epoch"), s.get("migration", {}).get("interval"),
       c.get("budget", {}).get("target_rms_percent"), c.get("resolution", {}).get("stall_on_finest"))
want = ("set-s3", 3, "straight", 16, 12, 7, 0.10, True)
if got != want:
    sys.exit(f"check-recipes: study.sh --set wrote {got}, expected {want}")
EOF
if COORDINATOR="$study/coordinator" deploy/study.sh run "$study/out" configs/circular_arc_finest4.toml \
  --set islands=16 --label bad 1 >/dev/null 2>&1; then
  echo "check-recipes: study.sh accepted --set without a section" >&2
  exit 1
fi
# study.sh resume (how a study cut short, here or on a lent machine, is finished): a finished run is
# left alone, a run with a store continues it, one without starts again, and each config is pointed
# at the study's folder, wherever the study was made.
mkdir -p "$study/res/configs" "$study/res/r-s1" "$study/res/r-s2"
for seed in 1 2 3; do printf 'name = "r-s%s"\nseed = %s\nresults_dir = "/elsewhere"\n' $seed $seed > "$study/res/configs/r-s$seed.toml"; done
echo '{}' > "$study/res/r-s1/summary.json"
: > "$study/res/r-s2/run.sqlite"
printf '#!/bin/sh\necho "$* $(grep results_dir "$2")" >> "%s/calls"\n' "$study" > "$study/record"
chmod +x "$study/record"
COORDINATOR="$study/record" deploy/study.sh resume "$study/res" --jobs 2 2>/dev/null
got=$(sort "$study/calls")
res=$(cd "$study/res" && pwd)
want="--config $study/res/configs/r-s2.toml --local-workers 1 --resume results_dir = \"$res\"
--config $study/res/configs/r-s3.toml --local-workers 1 --fresh results_dir = \"$res\""
if [ "$got" != "$want" ]; then
  printf 'check-recipes: study.sh resume ran\n%s\nexpected\n%s\n' "$got" "$want" >&2
  exit 1
fi
# study.sh summary (the docs' island curves rely on it): two settings of two runs each, one run
# stopped short of the paper's value, which counts as later than any run that reached it; two
# runs a signal stopped, one after it reached the value (counted) and one before (left out, as
# its count is not known yet), and one with no summary (still going, or killed: left out).
fake_run() { # <name> <seed> <evaluations at which the paper's 0.10 % was reached, or "never"> [<stop>]
  local dir="$study/sum/$1-s$2"
  mkdir -p "$dir"
  printf 'seed = %s\n[scene]\ntarget = "straight"\n[resolution]\nlevels = [[12, 40, 12]]\n' "$2" > "$dir/config.toml"
  printf 'epoch,evaluations,wall_seconds,resolution,island,best_fitness,best_rms_percent\n' > "$dir/history.csv"
  printf '1,100,1.0,12x40x12,0,-1,0.5\n' >> "$dir/history.csv"
  if [ "$3" = never ]; then stop=budget; else stop=target_reached
    printf '2,%s,2.0,12x40x12,0,-1,0.09\n' "$3" >> "$dir/history.csv"; fi
  stop=${4:-$stop}
  [ "$stop" = none ] || printf '{"stop": "%s"}' "$stop" > "$dir/summary.json"
}
fake_run stra-1x48 1 1000; fake_run stra-1x48 2 3000; fake_run stra-1x48 3 4000 shutdown
fake_run stra-16x3 1 2000; fake_run stra-16x3 2 never
fake_run stra-16x3 3 never shutdown; fake_run stra-16x3 4 never none
got=$(deploy/study.sh summary "$study/sum" | tail -n 2)
want='| straight | stra-1x48 | 3 | 3 | 3,000 | 1,000–4,000 | – |
| straight | stra-16x3 | 2 | 1 | beyond | 2,000–beyond | 0.33 |'
if [ "$got" != "$want" ]; then
  printf 'check-recipes: study.sh summary printed\n%s\nexpected\n%s\n' "$got" "$want" >&2
  exit 1
fi
# study.sh handovers (the handover bench's CSV): a run that ended at its switch to the final level
# (its history has no final-level row; the summary has the design it handed over) is listed with
# its evaluations and error there, a whole run is not.
handover_run() { # <name> <seed> <final-level row or "none">
  local dir="$study/ho/$1-s$2"
  mkdir -p "$dir"
  printf 'seed = %s\n[search]\nislands = 8\npopulation = 6\n[scene]\ntarget = "circular_arc"\n[resolution]\nlevels = [[6, 20, 6], [12, 40, 12]]\n' "$2" > "$dir/config.toml"
  printf 'epoch,evaluations,wall_seconds,resolution,island,best_fitness,best_rms_percent\n1,96,1.0,6x20x6,0,-1,0.4\n' > "$dir/history.csv"
  [ "$3" = none ] || printf '2,%s,2.0,12x40x12,0,-1,0.09\n' "$3" >> "$dir/history.csv"
  printf '{"stop": "target_reached", "resolution": "12x40x12", "evaluations": 145, "best_rms_percent": 0.8125}' > "$dir/summary.json"
}
handover_run ho-8x6 4 none; handover_run whole-8x6 5 190
got=$(deploy/study.sh handovers 47 "$study/ho")
want='target,islands,population,seed,switch_evaluations,handover_rms_percent,session
circular_arc,8,6,4,145,0.8125,47'
if [ "$got" != "$want" ]; then
  printf 'check-recipes: study.sh handovers printed\n%s\nexpected\n%s\n' "$got" "$want" >&2
  exit 1
fi
echo "check-recipes: Kubernetes manifests valid, scripts parse, study.sh --set edits configs, study.sh resume finishes what a stop cut short, study.sh summary ranks settings, study.sh handovers lists hand-overs"
