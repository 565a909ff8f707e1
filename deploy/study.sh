#!/usr/bin/env bash
# Reproducible search studies (docs/evolution.md): runs one config over several seeds, each a
# fresh single-coordinator run with one local worker, and tabulates what the runs wrote.
#
#   deploy/study.sh run <out> <config.toml> [--extra <snippet.toml>] [--set <section.key=value>]...
#                       [--target <rms %>] [--label <l>] <seed>...
#   deploy/study.sh table <out> [<out>...]
#
# `run` copies the config per seed with `name = <label>-s<seed>`, `seed = <seed>` and
# `results_dir = <out>`, appends the TOML snippet (sections the config does not already have,
# e.g. `[search.local_search]`), replaces each `--set` key in its section (`--set scene.target=straight
# --set search.islands=16`: a value that is not TOML is taken as a string; a missing key or section
# is added), sets `budget.target_rms_percent`, and runs the seeds one after
# another; start two `run`s to use two cores. `table` prints one markdown row per run from its
# config.toml, summary.json and history.csv: the best RMS error at the final resolution, and the
# evaluations at which the run first reached the paper's simulated error (Table III) and half of it,
# and the count at the final level's first epoch (how many of them the coarser levels took).
# COORDINATOR overrides the binary (default target/release/coordinator).
set -euo pipefail

usage() {
    sed -n '4,7p' "$0" | sed 's/^# *//' >&2
    exit 2
}

run() {
    local out=$1 config=$2
    shift 2
    local extra="" target="" label sets=()
    label=$(basename "$config" .toml)
    while [[ $# -gt 0 && $1 == --* ]]; do
        case $1 in
        --extra) extra=$2 ;;
        --set) sets+=("$2") ;;
        --target) target=$2 ;;
        --label) label=$2 ;;
        *) usage ;;
        esac
        shift 2
    done
    [[ $# -gt 0 ]] || usage
    local bin=${COORDINATOR:-target/release/coordinator}
    [[ -x $bin ]] || { echo "study: no coordinator binary at $bin (cargo build --release)" >&2; exit 1; }
    mkdir -p "$out/configs" "$out/logs"
    for seed in "$@"; do
        local name="$label-s$seed" file="$out/configs/$label-s$seed.toml"
        {
            echo "name = \"$name\""
            echo "seed = $seed"
            echo "results_dir = \"$(cd "$out" && pwd)\""
            grep -Ev '^(name|seed|results_dir)[[:space:]]*=' "$config" |
                if [[ -n $target ]]; then
                    sed -E "s/^target_rms_percent[[:space:]]*=.*/target_rms_percent = $target/"
                else
                    cat
                fi
            if [[ -n $extra ]]; then
                echo
                cat "$extra"
            fi
        } >"$file"
        if [[ ${#sets[@]} -gt 0 ]]; then
            set_keys "$file" "${sets[@]}" || exit 2
        fi
        echo "study: $name started $(date -Is), load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
        "$bin" --config "$file" --local-workers 1 --fresh >"$out/logs/$name.log" 2>&1 ||
            echo "study: $name failed, see $out/logs/$name.log" >&2
        echo "study: $name ended $(date -Is), load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
    done
}

# Rewrites `key = …` inside `[section]` of a config in place, for each `section.key=value`; the
# result must still parse as TOML, so a typo stops the study here and not half-way through it.
set_keys() {
    python3 - "$@" <<'EOF'
import re, sys, tomllib

path, assignments = sys.argv[1], sys.argv[2:]
lines = open(path).read().split("\n")
for assignment in assignments:
    dotted, sep, value = assignment.partition("=")
    if not sep or "." not in dotted:
        sys.exit(f"study: --set {assignment!r}: expected section.key=value")
    section, key = dotted.strip().rsplit(".", 1)
    try:
        tomllib.loads(f"v = {value}")
    except tomllib.TOMLDecodeError:
        value = '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    header = f"[{section}]"
    start = next((i for i, l in enumerate(lines) if l.strip() == header), None)
    if start is None:
        lines += ["", header, f"{key} = {value}"]
        continue
    end = next((i for i in range(start + 1, len(lines)) if lines[i].lstrip().startswith("[")), len(lines))
    pattern = re.compile(rf"^\s*{re.escape(key)}\s*=")
    hit = next((i for i in range(start + 1, end) if pattern.match(lines[i])), None)
    if hit is None:
        lines.insert(start + 1, f"{key} = {value}")
    else:
        lines[hit] = f"{key} = {value}"
text = "\n".join(lines)
try:
    tomllib.loads(text)
except tomllib.TOMLDecodeError as e:
    sys.exit(f"study: {path} after --set: {e}")
open(path, "w").write(text)
EOF
}

table() {
    python3 - "$@" <<'EOF'
import csv, json, pathlib, sys, tomllib

# The paper's simulated RMS errors (Table III), percent of the tip deflection.
PAPER = {"straight": 0.10, "circular_arc": 0.10, "discontinuous_slope": 0.86, "polynomial4": 0.90}

print("| run | target | seed | evaluations | stop | final level from | best RMS % (final level) | paper | reached paper at | reached half at | wall s |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for out in sys.argv[1:]:
    for run in sorted(p for p in pathlib.Path(out).iterdir() if (p / "history.csv").exists()):
        config = tomllib.loads((run / "config.toml").read_text())
        target = config.get("scene", {}).get("target")
        final = "x".join(str(n) for n in config["resolution"]["levels"][-1])
        rows = list(csv.DictReader(open(run / "history.csv")))
        rms_key = next(k for k in rows[0] if k.startswith("best_") and k != "best_fitness")
        paper = PAPER.get(target)
        # (evaluations, best RMS) at the final level, in order; the first one's count includes the
        # switch's re-evaluations and that epoch's children.
        points = [(int(r["evaluations"]), float(r[rms_key])) for r in rows
                  if r["resolution"] == final and r[rms_key]]
        evals, wall = int(rows[-1]["evaluations"]), float(rows[-1]["wall_seconds"])
        summary = run / "summary.json"
        summary = json.loads(summary.read_text()) if summary.exists() else {}
        stop = summary.get("stop", "running")
        wall = summary.get("wall_seconds", wall)
        # A run can meet its target in the re-evaluation at a switch, before the final level's
        # first epoch writes a history row: then only the summary has the final state.
        if summary.get("best_rms_percent") is not None and summary.get("resolution") == final:
            evals = summary["evaluations"]
            points.append((evals, summary["best_rms_percent"]))
        start = points[0][0] if points else None
        best = min((v for _, v in points), default=None)
        first = {}
        for name, level in (("paper", paper), ("half", paper and paper / 2)):
            hit = next((n for n, v in points if level is not None and v <= level), None)
            if hit is not None:
                first[name] = hit
        fmt = lambda v: "–" if v is None else f"{v:.4g}"
        print(f"| {run.name} | {target} | {config['seed']} | {evals} | {stop} | {start or '–'} | {fmt(best)} | "
              f"{fmt(paper)} | {first.get('paper', '–')} | {first.get('half', '–')} | {wall:.0f} |")
EOF
}

case ${1:-} in
run)
    shift
    [[ $# -ge 3 ]] || usage
    run "$@"
    ;;
table)
    shift
    [[ $# -ge 1 ]] || usage
    table "$@"
    ;;
*) usage ;;
esac
