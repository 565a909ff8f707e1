#!/usr/bin/env bash
# Opens a design's fabrication files in independent readers (run by .ci/run):
# - every per-material STL in admesh (Debian's package, installed if missing): no facet it had to
#   remove, add, reverse or fix, no backwards edge, and the volume the voxel count gives;
# - the 3MF in lib3mf's strict reader (PyPI, in a virtualenv under target/): no warning, one
#   named, manifold and oriented object per material with the STL's triangle count.
# The design is tests/fixtures/circular_arc_beam.json (an evolved beam, 1 mm voxels). Each check
# is also run on a damaged copy, which it must refuse.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
source deploy/checker-tools.sh
debian_package admesh admesh
venv="$root/target/exports-venv"
python_tools "$venv" lib3mf lib3mf
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
cargo run --quiet --locked --bin worker -- export --genome tests/fixtures/circular_arc_beam.json \
  --scene configs/circular_arc.toml --resolution 12x40x12 --out "$out" > "$out/export.txt"

# admesh on one STL: prints "ok <facets> <volume>" or the first complaint.
stl_check() {
  admesh "$1" | awk '
    /^Number of facets/ { facets = $NF }
    /Volume/ { volume = $NF }
    /^(Degenerate facets|Edges fixed|Facets removed|Facets added|Facets reversed|Backwards edges)/ {
      if ($NF != 0) { bad = bad $0 "; " } }
    END { if (bad != "") print "bad " bad; else print "ok", facets, volume }'
}
for stl in "$out"/material-*.stl; do
  result="$(stl_check "$stl")"
  case "$result" in
    ok*) echo "check-exports: admesh $(basename "$stl"): $result" ;;
    *) echo "check-exports: admesh $(basename "$stl"): $result" >&2; exit 1 ;;
  esac
done
# Together the materials enclose the design's volume: the worker's "<N> voxels" of 1 mm³.
total="$(stl_check "$out"/material-0-*.stl | awk '{print $3}')"
total="$(awk -v a="$total" -v b="$(stl_check "$out"/material-1-*.stl | awk '{print $3}')" 'BEGIN { print a + b }')"
voxels="$(awk '{print $1; exit}' "$out/export.txt")"
awk -v v="$total" -v n="$voxels" 'BEGIN { if (v < n - 0.05 || v > n + 0.05) { print "check-exports: STL volume " v " mm3 is not the " n " voxels of 1 mm3" > "/dev/stderr"; exit 1 } }'
# The STL check must be able to fail: reverse one triangle (swap two vertices of facet 1).
python3 - "$out"/material-1-*.stl "$out/reversed.stl" <<'PY'
import sys
data = bytearray(open(sys.argv[1], "rb").read())
first = 84  # header, count; then per facet: normal (12), three vertices (36), attribute (2)
data[first + 12:first + 24], data[first + 24:first + 36] = data[first + 24:first + 36], data[first + 12:first + 24]
open(sys.argv[2], "wb").write(data)
PY
if stl_check "$out/reversed.stl" | grep -q '^ok'; then
  echo "check-exports: admesh accepted an STL with a reversed facet" >&2
  exit 1
fi

"$venv/bin/python" - "$out/design.3mf" <<'PY'
import sys, zipfile, lib3mf
wrapper = lib3mf.get_wrapper()

def read(path):
    model = wrapper.CreateModel()
    reader = model.QueryReader("3mf")
    reader.SetStrictModeActive(True)
    reader.ReadFromFile(path)
    warnings = [reader.GetWarning(i)[1] for i in range(reader.GetWarningCount())]
    objects = []
    meshes = model.GetMeshObjects()
    while meshes.MoveNext():
        m = meshes.GetCurrentMeshObject()
        objects.append((m.GetName(), m.GetTriangleCount(), m.IsManifoldAndOriented()))
    return warnings, objects

warnings, objects = read(sys.argv[1])
assert not warnings, f"lib3mf warnings: {warnings}"
assert len(objects) == 2, objects
for name, triangles, manifold in objects:
    assert name and manifold and triangles > 0, objects
print(f"check-exports: lib3mf {'.'.join(map(str, wrapper.GetLibraryVersion()))} strict: {objects}")
# The 3MF check must be able to fail: a copy whose model drops one triangle is no longer manifold.
damaged = sys.argv[1] + ".damaged.3mf"
with zipfile.ZipFile(sys.argv[1]) as src, zipfile.ZipFile(damaged, "w") as dst:
    for item in src.infolist():
        data = src.read(item.filename)
        if item.filename.endswith(".model"):
            text = data.decode()
            start = text.index("<triangle ")
            text = text[:start] + text[text.index("/>", start) + 2:]
            data = text.encode()
        dst.writestr(item, data)
_, objects = read(damaged)
assert not all(manifold for _, _, manifold in objects), "lib3mf found a damaged mesh manifold"
PY
echo "check-exports: STLs and 3MF read cleanly by admesh and lib3mf; damaged copies refused"
