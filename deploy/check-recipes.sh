#!/usr/bin/env bash
# Checks the cluster recipes beyond one machine, as far as this machine allows (run by .ci/run):
# - the Kubernetes manifests validate against the Kubernetes API schemas (kubernetes-validate from
#   PyPI, installed into a virtualenv under target/), and a broken manifest is caught;
# - the shell scripts, including the Slurm batch script, parse.
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
echo "check-recipes: Kubernetes manifests valid, scripts parse"
