#!/usr/bin/env bash
# Instructions per Scene.evaluate call from Python against the same evaluation called in Rust,
# counted by callgrind (repeatable on a shared, noisy machine, unlike seconds). Each side runs 2
# and then 6 calls; the difference over 4 is the marginal cost of one call, start-up excluded.
# Run from the repository's root with the package installed: python/benches/overhead_instructions.sh
set -euo pipefail
python="${PYTHON:-python3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cargo bench -q -p amorph-python --bench evaluate_call --no-run 2>/dev/null
bench="$(ls -t target/release/deps/evaluate_call-* | grep -v '\.d$' | head -1)"
"$python" - "$work/genome.json" <<'PY'
import sys
sys.path.insert(0, "python/benches")
import amorph, overhead
overhead.genome(amorph.Scene.from_file("configs/quickstart.toml")).save(sys.argv[1])
PY
cat > "$work/calls.py" <<PY
import sys, amorph
scene = amorph.Scene.from_file("configs/quickstart.toml")
g = amorph.Genome.load("$work/genome.json")
for _ in range(int(sys.argv[1])):
    scene.evaluate(g, "6x20x6")
PY
count() { valgrind --tool=callgrind --callgrind-out-file="$work/cg" "$@" 2>&1 | sed -n 's/.*Collected : //p'; }
py2=$(count "$python" "$work/calls.py" 2); py6=$(count "$python" "$work/calls.py" 6)
rs2=$(count "$bench" "$work/genome.json" 6x20x6 2); rs6=$(count "$bench" "$work/genome.json" 6x20x6 6)
echo "python: $(( (py6 - py2) / 4 )) instructions per call"
echo "rust:   $(( (rs6 - rs2) / 4 )) instructions per call"
"$python" -c "print(f'python / rust: {($py6 - $py2) / ($rs6 - $rs2):.4f}')"
