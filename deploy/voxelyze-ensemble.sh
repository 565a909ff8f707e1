#!/usr/bin/env bash
# Compares our travel with the VoxCAD-era Voxelyze's over an ensemble of imperceptibly different
# starts (docs/how-to/voxelyze.md). A walking gait is a chaotic
# contact problem: a design's 10-cycle travel in either program can move by a quarter when its
# actuation starts a few microseconds later. So one run per program compares two samples of two
# spreads; this script runs N and compares the spreads.
#
#   deploy/voxelyze-ensemble.sh VOXELYZE CONFIG RESOLUTION N GENOME.json...
#
# CONFIG is a run's config.toml as the run wrote it (every key). Member k of the ensemble shifts
# the scene's actuation phase by 2π·k·1e-4 (k/10,000 of a period: 7 µs at the paper's 0.07 s,
# physically nothing); ours is evaluated at the exported file's step fraction with the reader's
# contact laws (actuated_contact, friction = "voxcad"), and the file is exported from that same
# scene, so it carries the settle ours measures and the shifted phase (in <PhaseOffset>): both
# programs see the same perturbation.
# Prints a Markdown row per design: each program's median travel along x, its range, the ratio of
# the medians, and how many of the N pairs are within ±25 % of each other.
set -euo pipefail
if [ $# -lt 5 ]; then
  sed -n '2,16p' "$0" >&2
  exit 2
fi
reader="$(realpath "$1")"; scene="$(realpath "$2")"; resolution="$3"; members="$4"; shift 4
[[ $members =~ ^[1-9][0-9]*$ ]] || { echo "voxelyze-ensemble: N must be a positive count, not '$members'" >&2; exit 2; }
[ "$(grep -c '^phase = ' "$scene")" = 1 ] || {
  echo "voxelyze-ensemble: $scene must hold exactly one 'phase = ' line (a run's own config.toml)" >&2
  exit 2
}
root="$(cd "$(dirname "$0")/.." && pwd)"
tool=voxelyze-ensemble
source "$root/deploy/voxelyze-common.sh"
worker="$(voxelyze_worker "$root" "$reader")"
require_floor_table "$scene"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
echo "| design | voxels | ours: median x (range), mm | the reader: median x (range), mm | reader ÷ ours (medians) | pairs within ±25 % |"
echo "|---|---|---|---|---|---|"
for genome in "$@"; do
  name="$(basename "$genome" .json)"
  : > "$out/$name.pairs"
  for ((k = 0; k < members; k++)); do
    dir="$out/$name/$k"
    mkdir -p "$dir"
    phase="$(python3 -c "import math; print(repr(2 * math.pi * $k * 1e-4))")"
    # One start per member: the ensemble is itself the comparison over starts, and a member's file
    # runs one start in the reader ([scene.starts] count, if the run used several).
    reader_floor_scene "$scene" "s/^phase = .*/phase = $phase/" \
      '/^\[scene\.starts\]$/,/^\[/ s/^count = .*/count = 1/' > "$dir/scene.toml"
    # Export once to learn the step the file asks the reader for, then export again from a scene
    # at that step, so that the settle the file carries is the one ours measures.
    "$worker" export --genome "$genome" --scene "$dir/scene.toml" --resolution "$resolution" --out "$dir" > /dev/null
    step="$(grep -o '<DtFrac>[^<]*' "$dir/design.vxa" | cut -d'>' -f2)"
    sed -i "s/^dt_fraction = .*/dt_fraction = $step/" "$dir/scene.toml"
    "$worker" export --genome "$genome" --scene "$dir/scene.toml" --resolution "$resolution" --out "$dir" > /dev/null
    "$worker" evaluate --genome "$genome" --scene "$dir/scene.toml" --resolution "$resolution" > "$dir/ours.json"
    run_reader "$reader" "$dir" "$genome (member $k)"
    python3 - "$dir/ours.json" "$dir/fitness.xml" >> "$out/$name.pairs" <<'PY'
import json, sys, xml.etree.ElementTree as ET
ours = json.load(open(sys.argv[1]))["evaluated"]["metrics"]["locomotion"]
steps = ET.parse(sys.argv[2]).getroot().findall("./CMTrace/TraceStep")
if len(steps) < 2:
    sys.exit(f"voxelyze-ensemble: {sys.argv[2]} holds no centre-of-mass trace")
dx = float(steps[-1].find("TraceX").text) - float(steps[0].find("TraceX").text)
print(ours["voxels"], ours["displacement"] * 1e3, dx * 1e3)
PY
  done
  python3 - "$out/$name.pairs" "$name" <<'PY'
import statistics, sys
rows = [line.split() for line in open(sys.argv[1])]
voxels = rows[0][0]
ours = [float(r[1]) for r in rows]
reader = [float(r[2]) for r in rows]
within = sum(1 for o, r in zip(ours, reader) if o != 0 and 0.75 <= r / o <= 1.25)
mo, mr = statistics.median(ours), statistics.median(reader)
print(f"| {sys.argv[2]} | {voxels} | {mo:+.2f} ({min(ours):+.2f} … {max(ours):+.2f}) "
      f"| {mr:+.2f} ({min(reader):+.2f} … {max(reader):+.2f}) | {mr / mo:.2f} | {within} of {len(rows)} |")
PY
done
