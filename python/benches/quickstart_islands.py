"""The quickstart's islands study (docs/explanation/search.md#islands-and-migration).

Question: does the quickstart reach the paper's 0.10 % on the circular arc in fewer evaluations
with four islands of 12 (one shared climb, the same 48 children an epoch) than with the one island
of 48 it runs today? Runs: seeds 1-5 of each, configs/quickstart.toml as it is (8,000 evaluations
at most, stop at 0.10 %), two local workers. Measure: the evaluations the run spent (8,000 for a
run that stops by its budget). Rule, fixed before the runs: four islands become the quickstart's
if their median is at least 10 % lower and they are lower on at least four of the five seeds;
otherwise the quickstart stays as it is.

    python python/benches/quickstart_islands.py [RESULTS_DIR]   # from the repository's root

Runs what RESULTS_DIR (default target/quickstart-islands) does not hold yet, in the order seed 1
one island, seed 1 four islands, seed 2 ..., and prints the table. The coordinator is
target/release/coordinator, or $AMORPH_COORDINATOR (a debug build gives the same bits, slower).
No Python packages."""

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SEEDS = [1, 2, 3, 4, 5]
ARMS = {
    "one48": [],
    "four12": ["search.islands=4", "search.population=12", "search.children_per_epoch=12"],
}


def run(results, arm, seed):
    name = f"{arm}-{seed}"
    summary = results / name / "summary.json"
    if not summary.exists():
        coordinator = os.environ.get("AMORPH_COORDINATOR", str(ROOT / "target/release/coordinator"))
        sets = [f'name="{name}"', f'results_dir="{results}"', f"seed={seed}", *ARMS[arm]]
        command = [coordinator, "--config", str(ROOT / "configs/quickstart.toml"), "--fresh"]
        for s in sets:
            command += ["--set", s]
        subprocess.run(command, check=True, capture_output=True)
    return json.loads(summary.read_text())


def main():
    results = Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "target/quickstart-islands").resolve()
    rows = {arm: {} for arm in ARMS}
    for seed in SEEDS:
        for arm in ARMS:
            s = run(results, arm, seed)
            rows[arm][seed] = (s["evaluations"], s["best_rms_percent"], s["stop"])
            print(f"seed {seed} {arm}: {s['evaluations']} evaluations, {s['best_rms_percent']:.5f} %, {s['stop']}",
                  flush=True)
    medians = {arm: statistics.median(v[0] for v in rows[arm].values()) for arm in ARMS}
    fewer = sum(rows["four12"][s][0] < rows["one48"][s][0] for s in SEEDS)
    print(f"median evaluations: one island of 48 {medians['one48']:.0f}, four of 12 {medians['four12']:.0f}; "
          f"four of 12 fewer on {fewer} of {len(SEEDS)} seeds")
    wins = medians["four12"] <= 0.9 * medians["one48"] and fewer >= 4
    print("four islands of 12 win" if wins else "the quickstart stays as it is")


if __name__ == "__main__":
    main()
