#!/usr/bin/env bash
# Runs robots' exported design.vxa through another Voxelyze build and prints, per design, our
# centre-of-mass travel beside the reader's (docs/how-to/voxelyze.md). The reader is not part of
# this repository: build it from its public sources as the docs say and pass its `voxelyze`
# binary.
#
#   deploy/voxelyze-check.sh VOXELYZE CONFIG RESOLUTION GENOME.json...
#
# CONFIG is a run's config.toml as the run wrote it (results/<run>/config.toml: every key,
# [scene.dynamics] included). For each genome: `worker evaluate` at the scene's own time step (the
# search's figure) and at the step the exported file asks the reader for (its DtFrac, at most 0.9:
# the reader's floor drifts at 1.0), `worker export` (the files as a user gets them, unedited),
# then `voxelyze -f design.vxa` in the export folder; the reader's travel is read from the
# centre-of-mass trace in its result file (its own distance is unsigned). Ours is also evaluated at
# the file's step with the reader's contact laws ([scene.dynamics.floor] actuated_contact = true,
# friction = "voxcad"), which separates what the file says from how the two simulators' floors
# differ. Prints a Markdown table row per design.
#
# DTFRAC=<f> runs both programs at step fraction f instead of the file's (the file's <DtFrac> is
# rewritten after export, ours is evaluated at dt_fraction = f): a walking gait is a chaotic contact
# problem, so the comparison at several steps tells the programs' difference from each one's own
# step sensitivity (docs/how-to/voxelyze.md).
set -euo pipefail
if [ $# -lt 4 ]; then
  sed -n '2,15p' "$0" >&2
  exit 2
fi
reader="$(realpath "$1")"; scene="$(realpath "$2")"; resolution="$3"; shift 3
grep -q '^dt_fraction = ' "$scene" || {
  echo "voxelyze-check: $scene has no dt_fraction line; give a run's own config.toml" >&2
  exit 2
}
root="$(cd "$(dirname "$0")/.." && pwd)"
tool=voxelyze-check
source "$root/deploy/voxelyze-common.sh"
worker="$(voxelyze_worker "$root" "$reader")"
require_floor_table "$scene"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
echo "| design | voxels | settle | ours: travel x (fitness), y | ours at the file's step: x, y | the reader: x, y | reader / ours at the file's step (x) | ours at the file's step with the reader's contact laws: x, y | reader / that (x) |"
echo "|---|---|---|---|---|---|---|---|---|"
for genome in "$@"; do
  name="$(basename "$genome" .json)"
  dir="$out/$name"
  mkdir -p "$dir"
  "$worker" evaluate --genome "$genome" --scene "$scene" --resolution "$resolution" > "$dir/ours.json"
  "$worker" export --genome "$genome" --scene "$scene" --resolution "$resolution" --out "$dir" > /dev/null
  if [ -n "${DTFRAC:-}" ]; then
    sed -i "s|<DtFrac>[^<]*|<DtFrac>$DTFRAC|" "$dir/design.vxa"
  fi
  step="$(grep -o '<DtFrac>[^<]*' "$dir/design.vxa" | cut -d'>' -f2)"
  sed "s/^dt_fraction = .*/dt_fraction = $step/" "$scene" > "$dir/at-file-step.toml"
  "$worker" evaluate --genome "$genome" --scene "$dir/at-file-step.toml" --resolution "$resolution" > "$dir/ours-at-file-step.json"
  reader_floor_scene "$dir/at-file-step.toml" > "$dir/reader-laws.toml"
  "$worker" evaluate --genome "$genome" --scene "$dir/reader-laws.toml" --resolution "$resolution" > "$dir/ours-reader-laws.json"
  run_reader "$reader" "$dir" "$genome"
  python3 - "$dir/ours.json" "$dir/ours-at-file-step.json" "$dir/fitness.xml" "$name" "$dir/ours-reader-laws.json" <<'PY'
import json, sys, xml.etree.ElementTree as ET
metrics = lambda f: json.load(open(f))["evaluated"]["metrics"]["locomotion"]
ours, same_step, laws = metrics(sys.argv[1]), metrics(sys.argv[2]), metrics(sys.argv[5])
steps = ET.parse(sys.argv[3]).getroot().findall("./CMTrace/TraceStep")
if len(steps) < 2:
    sys.exit(f"voxelyze-check: {sys.argv[3]} holds no centre-of-mass trace")
first, last = steps[0], steps[-1]
dx = (float(last.find("TraceX").text) - float(first.find("TraceX").text)) * 1e3
dy = (float(last.find("TraceY").text) - float(first.find("TraceY").text)) * 1e3
x, fit, y = ours["displacement"] * 1e3, ours["gait_displacement"] * 1e3, ours["lateral"] * 1e3
x9, y9 = same_step["displacement"] * 1e3, same_step["lateral"] * 1e3
xl, yl = laws["displacement"] * 1e3, laws["lateral"] * 1e3
print(f"| {sys.argv[4]} | {ours['voxels']} | {ours['settle_time']:.3f} s | {x:+.2f} mm ({fit:.2f}), {y:+.2f} mm "
      f"| {x9:+.2f} mm, {y9:+.2f} mm | {dx:+.2f} mm, {dy:+.2f} mm | {dx / x9:.2f} "
      f"| {xl:+.2f} mm, {yl:+.2f} mm | {dx / xl:.2f} |")
PY
done
