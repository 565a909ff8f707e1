"""The quickstart's hand-over study (docs/explanation/search.md#multi-resolution-bootstrapping).

Question: does the quickstart reach the paper's 0.10 % on the circular arc with less computing if
the coarse level gives way by the paper's stall rule (the coarse best's own fitness) instead of
`stall_on_finest` (its score on the finest grid)? An evaluation at 12x40x12 costs about ten at
6x20x6, so the measure is the evaluations the run spent at 12x40x12. The paper's rule was seen to
spend fewer of them on the arc in earlier runs (search.md), while needing more evaluations in all.
Runs: seeds 1-5 of each, configs/quickstart.toml as it is (8,000 evaluations at most, stop at
0.10 %), two local workers. Rule, fixed before the runs: the paper's rule becomes the quickstart's
if it reaches 0.10 % on at least as many seeds, its median of 12x40x12 evaluations is at least
10 % lower, and it is lower on at least four of the five seeds (a run that stops by its budget
counts as its 12x40x12 evaluations, and as not reaching); otherwise the quickstart stays as it is.

    python python/benches/quickstart_handover.py [RESULTS_DIR]   # from the repository's root

Runs what RESULTS_DIR (default target/quickstart-handover) does not hold yet, in the order seed 1
stall_on_finest, seed 1 the paper's rule, seed 2 ..., and prints the table. The coordinator is
target/release/coordinator, or $AMORPH_COORDINATOR (a debug build gives the same bits, slower).
No Python packages."""

import json
import os
import sqlite3
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SEEDS = [1, 2, 3, 4, 5]
FINE = "12x40x12"
ARMS = {
    "finest": [],
    "paper_rule": ["resolution.stall_on_finest=false"],
}


def fine_evaluations(run):
    """Evaluations the run spent at 12x40x12, the finest-grid checks of the coarse level included."""
    store = sqlite3.connect(run / "run.sqlite")
    return store.execute("select count(*) from evaluation where resolution = ?", (FINE,)).fetchone()[0]


def run(results, arm, seed):
    name = f"{arm}-{seed}"
    folder = results / name
    if not (folder / "summary.json").exists():
        coordinator = os.environ.get("AMORPH_COORDINATOR", str(ROOT / "target/release/coordinator"))
        sets = [f'name="{name}"', f'results_dir="{results}"', f"seed={seed}", *ARMS[arm]]
        command = [coordinator, "--config", str(ROOT / "configs/quickstart.toml"), "--fresh"]
        for s in sets:
            command += ["--set", s]
        subprocess.run(command, check=True, capture_output=True)
    summary = json.loads((folder / "summary.json").read_text())
    return summary["evaluations"], fine_evaluations(folder), summary["stop"] == "target_reached"


def main():
    results = Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "target/quickstart-handover").resolve()
    rows = {arm: {} for arm in ARMS}
    for seed in SEEDS:
        for arm in ARMS:
            total, fine, reached = rows[arm][seed] = run(results, arm, seed)
            print(f"seed {seed} {arm}: {total} evaluations, {fine} at {FINE}, "
                  f"{'reached' if reached else 'not reached'}", flush=True)
    medians = {arm: statistics.median(v[1] for v in rows[arm].values()) for arm in ARMS}
    reached = {arm: sum(v[2] for v in rows[arm].values()) for arm in ARMS}
    fewer = sum(rows["paper_rule"][s][1] < rows["finest"][s][1] for s in SEEDS)
    print(f"median evaluations at {FINE}: stall_on_finest {medians['finest']:.0f}, the paper's rule "
          f"{medians['paper_rule']:.0f}; the paper's rule fewer on {fewer} of {len(SEEDS)} seeds; "
          f"reached on {reached['finest']} and {reached['paper_rule']} seeds")
    wins = (reached["paper_rule"] >= reached["finest"] and fewer >= 4
            and medians["paper_rule"] <= 0.9 * medians["finest"])
    print("the paper's rule wins" if wins else "the quickstart stays as it is")


if __name__ == "__main__":
    main()
