"""The robot trade-off study of docs/explanation/results.md#trade-offs: Pareto crowding against
NSGA-II on the walking robot, gait travel against voxels.

Question: which selection keeps the larger front on the robot? Runs: seeds 1-5 of each, the
robot of configs/locomotion_pareto.toml at 6x6x6 only, 1,500 evaluations. Measure: the
hypervolume of the run's front (every design evaluated so far that no other beats in both
objectives) against (0 mm, 216 voxels), after each evaluation, from the run's store. Rule: the
larger median at 1,500 evaluations wins if it is also larger on at least four of the five seeds;
otherwise neither does.

    python python/benches/robot_front_selection.py [RESULTS_DIR]   # from the repository's root

Runs what RESULTS_DIR (default target/robot-front-study) does not hold yet, then prints the
table and writes the median hypervolume against evaluations to docs/img/robot_front_hypervolume.svg.
Needs the release coordinator (cargo build --release --bin coordinator); no Python packages."""

import json
import sqlite3
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SEEDS = [1, 2, 3, 4, 5]
SELECTIONS = ["nsga2", "crowding"]
EVALUATIONS = 1500
REFERENCE = (0.0, 216.0)  # gait travel (mm, maximized), voxels (minimized): 6x6x6 holds 216
FIGURE = ROOT / "docs/img/robot_front_hypervolume.svg"


def run(results, selection, seed):
    name = f"robot-{selection}-{seed}"
    if not (results / name / "pareto.csv").exists():
        subprocess.run(
            [str(ROOT / "target/release/coordinator"), "--config", str(ROOT / "configs/locomotion_pareto.toml"),
             "--set", f'name="{name}"', "--set", f'results_dir="{results}"', "--set", f"seed={seed}",
             "--set", f'search.selection="{selection}"', "--set", "resolution.levels=[[6, 6, 6]]",
             "--set", "resolution.latest_switch=[]", "--set", f"budget.evaluations={EVALUATIONS}",
             "--set", f"search.hypervolume_reference=[{REFERENCE[0]}, {REFERENCE[1]}]", "--fresh"],
            check=True, capture_output=True)
    return results / name / "run.sqlite"


def points(store):
    """(travel mm, voxels) of each evaluation in the order the run made them; None for a failure."""
    rows = sqlite3.connect(store).execute("select outcome from evaluation order by task_id")
    out = []
    for (outcome,) in rows:
        evaluated = json.loads(outcome).get("evaluated")
        m = evaluated and evaluated["metrics"]["locomotion"]
        out.append(m and (1000.0 * m["gait_displacement"], m["voxels"]))
    return out


def hypervolume(front):
    """The area that a front of (travel, voxels) points dominates, bounded by REFERENCE."""
    area, best_travel = 0.0, REFERENCE[0]
    # From the fewest voxels up: each point adds the travel it gains over every smaller design.
    for travel, voxels in sorted(front, key=lambda p: (p[1], -p[0])):
        if travel > best_travel and voxels < REFERENCE[1]:
            area += (travel - best_travel) * (REFERENCE[1] - voxels)
            best_travel = travel
    return area


def curve(store):
    """The front's hypervolume after each evaluation."""
    front, out = [], []
    for p in points(store):
        if p and not any(q[0] >= p[0] and q[1] <= p[1] for q in front):
            front = [q for q in front if not (p[0] >= q[0] and p[1] <= q[1])] + [p]
        out.append(hypervolume(front))
    return out


def svg(curves):
    width, height, left, bottom, top, right = 640, 360, 70, 40, 20, 20
    top_value = max(max(c) for arm in curves.values() for c in arm) * 1.05
    x = lambda n: left + (width - left - right) * n / EVALUATIONS
    y = lambda v: height - bottom - (height - top - bottom) * v / top_value
    colors = {"nsga2": "#1f6feb", "crowding": "#d1242f"}
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" font-size="12">',
             f'<rect width="{width}" height="{height}" fill="white"/>',
             f'<line x1="{left}" y1="{height - bottom}" x2="{width - right}" y2="{height - bottom}" stroke="black"/>',
             f'<line x1="{left}" y1="{top}" x2="{left}" y2="{height - bottom}" stroke="black"/>']
    for n in range(0, EVALUATIONS + 1, 300):
        parts.append(f'<text x="{x(n):.1f}" y="{height - bottom + 15}" text-anchor="middle">{n}</text>')
    step = 10 ** len(str(int(top_value / 4))) // 10 or 1
    for v in range(0, int(top_value) + 1, max(step, int(top_value / 4) // step * step)):
        parts.append(f'<text x="{left - 6}" y="{y(v) + 4:.1f}" text-anchor="end">{v:,}</text>')
    parts.append(f'<text x="{(left + width - right) / 2}" y="{height - 6}" text-anchor="middle">evaluations</text>')
    parts.append(f'<text x="14" y="{(top + height - bottom) / 2}" text-anchor="middle" transform="rotate(-90 14 {(top + height - bottom) / 2})">hypervolume (mm x voxels)</text>')
    for i, (arm, runs) in enumerate(curves.items()):
        median = [statistics.median(c[n] for c in runs) for n in range(EVALUATIONS)]
        path = " ".join(f"{x(n + 1):.1f},{y(v):.1f}" for n, v in enumerate(median) if n % 10 == 9)
        parts.append(f'<polyline points="{path}" fill="none" stroke="{colors[arm]}" stroke-width="2"/>')
        parts.append(f'<text x="{width - right - 150}" y="{height - bottom - 20 - 16 * i}" fill="{colors[arm]}">{arm}, median of {len(runs)} seeds</text>')
    return "\n".join(parts + ["</svg>\n"])


def main():
    results = Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "target/robot-front-study").resolve()
    curves = {arm: [] for arm in SELECTIONS}
    print("| seed | " + " | ".join(f"{arm}: designs, hypervolume, best travel" for arm in SELECTIONS) + " |")
    for seed in SEEDS:
        cells = []
        for arm in SELECTIONS:
            store = run(results, arm, seed)
            c = curve(store)
            if len(c) != EVALUATIONS:
                sys.exit(f"{store}: {len(c)} evaluations, expected {EVALUATIONS}")
            curves[arm].append(c)
            with open(store.parent / "pareto.csv") as f:
                rows = [line.split(",") for line in f.read().split()[1:]]
            cells.append(f"{len(rows)}, {c[-1]:,.0f}, {max(float(r[1]) for r in rows):.2f} mm")
        print(f"| {seed} | " + " | ".join(cells) + " |")
    finals = {arm: [c[-1] for c in runs] for arm, runs in curves.items()}
    wins = sum(a > b for a, b in zip(finals["nsga2"], finals["crowding"]))
    print("| median | " + " | ".join(f"{statistics.median(finals[a]):,.0f}" for a in SELECTIONS) + " |")
    print(f"NSGA-II larger on {wins} of {len(SEEDS)} seeds")
    for n in (300, 750, 1500):
        print(f"median hypervolume at {n}: " + ", ".join(
            f"{a} {statistics.median(c[n - 1] for c in curves[a]):,.0f}" for a in SELECTIONS))
    FIGURE.write_text(svg(curves))
    print(f"wrote {FIGURE.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
