#!/usr/bin/env bash
# Reproducible search studies (docs/evolution.md): runs one config over several seeds, each a
# fresh single-coordinator run with one local worker, and tabulates what the runs wrote.
#
#   deploy/study.sh run <out> <config.toml> [--extra <snippet.toml>] [--set <section.key=value>]...
#                       [--target <rms %>] [--label <l>] <seed>...
#   deploy/study.sh resume <out> [--jobs <n>]
#   deploy/study.sh table <out> [<out>...]
#   deploy/study.sh summary <out> [<out>...]
#   deploy/study.sh handovers <session> <out> [<out>...]
#
# `run` copies the config per seed with `name = <label>-s<seed>`, `seed = <seed>` and
# `results_dir = <out>`, appends the TOML snippet (sections the config does not already have,
# e.g. `[search.local_search]`), replaces each `--set` key in its section (`--set scene.target=straight
# --set search.islands=16`: a value that is not TOML is taken as a string; a missing key or section
# is added), sets `budget.target_rms_percent`, and runs the seeds one after
# another; start two `run`s to use two cores. `resume` finishes every run of <out> that a stop cut
# short (one without summary.json, or whose summary says it was stopped), <n> at a time: it points
# the run's config at <out> (so a study copied from another machine or folder resumes where it now
# lies), then continues the run from its store with `--resume`, the bits it would have had
# uninterrupted, or starts it again if it stopped before writing one. `table` prints one markdown row per run from its
# config.toml, summary.json and history.csv: the best RMS error at the final resolution, and the
# evaluations at which the run first reached the paper's simulated error (Table III) and half of it,
# and the count at the final level's first epoch (how many of them the coarser levels took); a run
# with no summary.json shows as unfinished (still going, or killed), one a signal stopped as shutdown.
# `handovers` prints, as CSV for the handover bench (docs/data/handover.csv), every run that ended at
# its switch to the final level (one run with `--target 100`): the evaluations there, the
# switch's re-evaluations included, and the best design's RMS error on the final grid, before any
# of its children (the start of the finest level's climb), labelled with <session>.
# `summary` prints one row per setting (runs named <setting>-s<seed>) and target over the runs
# whose count is known (ended, or already past the paper's value): how many reached the paper's
# value, the median and quartiles of the evaluations to it (a run that ended short counts as
# beyond any budget), and the probability that a run of the setting
# gets there before a run of the setting with the fewest islands (the number before "x" in its name).
# That is a quick look while a study runs: for figures, put the runs in docs/data/island_curve.csv
# and run the island_curve bench, which counts a stopped run as censored at its count (Kaplan-Meier,
# coordinator/src/study.rs) instead of as the slowest. A policy key studied against the runs it
# changes (same settings and seeds, key on) goes in a CSV of its own, compared seed by seed with
# the paired_runs bench (docs/data/carry_checked.csv, docs/evolution.md session 35).
# COORDINATOR overrides the binary (default target/release/coordinator).
set -euo pipefail
# Bash reads a script as it runs it, and a study runs for hours: the whole script is one block
# (closed by `exit` below) so that bash has read all of it before it starts, and editing or
# checking out this file mid-study cannot make a running study re-run or skip a seed.
{

usage() {
    sed -n '4,10p' "$0" | sed 's/^# *//' >&2
    exit 2
}

# The coordinator binary the runs use, or a stop naming the one that is missing.
coordinator() {
    local bin=${COORDINATOR:-target/release/coordinator}
    [[ -x $bin ]] || { echo "study: no coordinator binary at $bin (cargo build --release)" >&2; exit 1; }
    echo "$bin"
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
    local bin
    bin=$(coordinator)
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

resume() {
    local out=$1 jobs=1
    shift
    while [[ $# -gt 0 ]]; do
        case $1 in
        --jobs) jobs=$2 ;;
        *) usage ;;
        esac
        shift 2
    done
    [[ $jobs =~ ^[1-9][0-9]*$ ]] || { echo "study: --jobs $jobs: expected a positive count" >&2; exit 2; }
    local bin
    bin=$(coordinator)
    [[ -d $out/configs ]] || { echo "study: $out/configs: no study there" >&2; exit 1; }
    local here file name mode
    here=$(cd "$out" && pwd)
    mkdir -p "$out/logs"
    for file in "$out"/configs/*.toml; do
        name=$(basename "$file" .toml)
        finished "$out/$name" && continue
        sed -i -E "s|^results_dir[[:space:]]*=.*|results_dir = \"$here\"|" "$file"
        mode=--fresh
        [[ -f $out/$name/run.sqlite ]] && mode=--resume
        while [[ $(jobs -rp | wc -l) -ge $jobs ]]; do wait -n || true; done
        (
            echo "study: $name $mode $(date -Is), load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
            "$bin" --config "$file" --local-workers 1 "$mode" >>"$out/logs/$name.log" 2>&1 ||
                echo "study: $name failed, see $out/logs/$name.log" >&2
            echo "study: $name ended $(date -Is)" >&2
        ) &
    done
    wait
}

# Whether a run ended on its own: a summary.json that is not a stop's (a coordinator asked to stop,
# by SIGTERM or ^C, writes one with `"stop": "shutdown"` and resumes from its store like any other).
finished() {
    [[ -f $1/summary.json ]] && ! grep -Eq '"stop":[[:space:]]*"shutdown"' "$1/summary.json"
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
import csv, json, math, pathlib, re, sys, tomllib

# The paper's simulated RMS errors (Table III), percent of the tip deflection.
PAPER = {"straight": 0.10, "circular_arc": 0.10, "discontinuous_slope": 0.86, "polynomial4": 0.90}


def read(run):
    """One run: what its config, summary.json and history.csv say."""
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
    # A run can meet its target in the re-evaluation at a switch, before the final level's
    # first epoch writes a history row: then only the summary has the final state.
    if summary.get("best_rms_percent") is not None and summary.get("resolution") == final:
        evals = summary["evaluations"]
        points.append((evals, summary["best_rms_percent"]))
    first = {}
    for name, level in (("paper", paper), ("half", paper and paper / 2)):
        hit = next((n for n, v in points if level is not None and v <= level), None)
        if hit is not None:
            first[name] = hit
    return {
        "name": run.name, "label": re.sub(r"-s\d+$", "", run.name), "target": target,
        "seed": config["seed"], "evaluations": evals, "stop": summary.get("stop", "unfinished"),
        "start": points[0][0] if points else None, "best": min((v for _, v in points), default=None),
        "paper": paper, "first": first, "wall": summary.get("wall_seconds", wall),
        "islands": config.get("search", {}).get("islands", 1),
        "population": config.get("search", {}).get("population"),
        # Ended at the switch: the summary is at the final level, which wrote no history row.
        "at_switch": summary.get("stop") == "target_reached" and summary.get("resolution") == final
        and not any(r["resolution"] == final for r in rows),
        "switch_rms": summary.get("best_rms_percent"),
    }


mode, outs = sys.argv[1], sys.argv[2:]
session = None
if mode == "handovers":
    session, outs = outs[0], outs[1:]
runs = [read(run) for out in outs for run in sorted(pathlib.Path(out).iterdir())
        if (run / "history.csv").exists()]
fmt = lambda v: "–" if v is None else f"{v:.4g}"
if mode == "table":
    print("| run | target | seed | evaluations | stop | final level from | best RMS % (final level) | paper | reached paper at | reached half at | wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in runs:
        print(f"| {r['name']} | {r['target']} | {r['seed']} | {r['evaluations']} | {r['stop']} | {r['start'] or '–'} | "
              f"{fmt(r['best'])} | {fmt(r['paper'])} | {r['first'].get('paper', '–')} | {r['first'].get('half', '–')} | {r['wall']:.0f} |")
    sys.exit()

if mode == "handovers":
    print("target,islands,population,seed,switch_evaluations,handover_rms_percent,session")
    for r in sorted((r for r in runs if r["at_switch"]),
                    key=lambda r: (r["target"], r["islands"], r["population"], r["seed"])):
        print(f"{r['target']},{r['islands']},{r['population']},{r['seed']},{r['evaluations']},"
              f"{r['switch_rms']:.6g},{session}")
    sys.exit()

# summary: one row per setting (a run's name less its "-s<seed>"), over the runs whose count is
# known. A run that ended for good (budget, wall time) short of the paper's value counts as
# infinitely late, so the median is the seeds' median whatever the budget. A run still going, or
# one a signal stopped (it resumes from its store), is left out unless it already reached the value.
def median(xs):
    xs, n = sorted(xs), len(xs)
    return xs[n // 2] if n % 2 else (xs[n // 2 - 1] + xs[n // 2]) / 2

def faster(a, b):
    """Probability that a run of `a` reaches the paper's value before a run of `b` (ties half):
    seeds are not paired across settings, so settings compare as samples."""
    pairs = [(x, y) for x in a for y in b]
    return sum(1.0 if x < y else 0.5 if x == y else 0.0 for x, y in pairs) / len(pairs)

groups = {}
for r in runs:
    if "paper" in r["first"] or r["stop"] not in ("unfinished", "shutdown"):
        groups.setdefault(r["target"], {}).setdefault(r["label"], []).append(r["first"].get("paper", math.inf))
show = lambda v: "beyond" if v == math.inf else f"{v:,.0f}"
print("| target | setting | runs | reached the paper's value | median evaluations to it | quartiles | P(faster than the first setting) |")
print("|---|---|---|---|---|---|---|")
# Settings in order of their island count (the number before an "x" in the label, as in
# "stra-16x3"), the first being the reference: one island, where the study has it.
islands = lambda l: int(m.group(1)) if (m := re.search(r"(?:^|-)(\d+)x", l)) else math.inf
for target in sorted(groups, key=str):
    labels = sorted(groups[target], key=lambda l: (islands(l), l))
    base = groups[target][labels[0]]
    for label in labels:
        hits = sorted(groups[target][label])
        q = lambda f: hits[round(f * (len(hits) - 1))]
        p = "–" if label == labels[0] else f"{faster(hits, base):.2f}"
        print(f"| {target} | {label} | {len(hits)} | {sum(h != math.inf for h in hits)} | {show(median(hits))} | "
              f"{show(q(0.25))}–{show(q(0.75))} | {p} |")
EOF
}

case ${1:-} in
run)
    shift
    [[ $# -ge 3 ]] || usage
    run "$@"
    ;;
resume)
    shift
    [[ $# -ge 1 ]] || usage
    resume "$@"
    ;;
table | summary)
    [[ $# -ge 2 ]] || usage
    table "$@"
    ;;
handovers)
    [[ $# -ge 3 ]] || usage
    table "$@"
    ;;
*) usage ;;
esac
exit
}
