"""The selection studies of docs/explanation/results.md#trade-offs: Pareto crowding against
NSGA-II, hypervolume against evaluations.

Question: which selection keeps the larger front? Runs: seeds 1-5 of each, on one problem:
- robot: configs/locomotion_pareto.toml at 6x6x6 only, 1,500 evaluations, gait travel against
  voxels, hypervolume against (0 mm, 216 voxels);
- beam: configs/beam_pareto.toml at 6x20x6 only, 6,000 evaluations, RMS error against voxels,
  hypervolume against (10 %, 720 voxels).
Measure: the hypervolume of the run's front (every design evaluated so far that no other beats in
both objectives) after each evaluation, from the run's store. Rule: the larger median at the end
wins if it is also larger on at least four of the five seeds; otherwise neither does.

    python python/benches/front_selection.py robot|beam [RESULTS_DIR]   # from the repository's root

Runs what RESULTS_DIR (default target/front-selection) does not hold yet, prints the table and
writes the median hypervolume against evaluations to docs/img/<problem>_front_hypervolume.svg.
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
# `objectives` reads a design's two objectives as the config names them; `sign` turns the first
# into one to minimize (the robot's travel is maximized), the voxels are minimized as they are.
PROBLEMS = {
    "robot": dict(config="locomotion_pareto.toml", level="[[6, 6, 6]]", evaluations=1500,
                  reference=(0.0, 216.0), first="best travel", unit="mm", sign=-1.0,
                  objectives=lambda m: (1000.0 * m["locomotion"]["gait_displacement"], m["locomotion"]["voxels"])),
    "beam": dict(config="beam_pareto.toml", level="[[6, 20, 6]]", evaluations=6000,
                 reference=(10.0, 720.0), first="best RMS", unit="%", sign=1.0,
                 objectives=lambda m: (m["beam"]["rms_percent"], m["beam"]["voxels"])),
}


def run(problem, results, selection, seed):
    name = f"{problem['name']}-{selection}-{seed}"
    reference = problem["reference"]
    if not (results / name / "pareto.csv").exists():
        subprocess.run(
            [str(ROOT / "target/release/coordinator"), "--config", str(ROOT / "configs" / problem["config"]),
             "--set", f'name="{name}"', "--set", f'results_dir="{results}"', "--set", f"seed={seed}",
             "--set", f'search.selection="{selection}"', "--set", f"resolution.levels={problem['level']}",
             "--set", "resolution.latest_switch=[]", "--set", f"budget.evaluations={problem['evaluations']}",
             "--set", f"search.hypervolume_reference=[{reference[0]}, {reference[1]}]", "--fresh"],
            check=True, capture_output=True)
    return results / name / "run.sqlite"


def minimized(problem, values):
    return (problem["sign"] * values[0], values[1])


def points(problem, store):
    """Each evaluation's minimized objectives, in the order the run made them; None for a failure."""
    rows = sqlite3.connect(store).execute("select outcome from evaluation order by task_id")
    out = []
    for (outcome,) in rows:
        evaluated = json.loads(outcome).get("evaluated")
        out.append(evaluated and minimized(problem, problem["objectives"](evaluated["metrics"])))
    return out


def hypervolume(front, reference):
    """The area that a front of minimized (first, voxels) points dominates up to the reference."""
    area, best = 0.0, reference[0]
    # From the fewest voxels up: each point adds what it gains in the first objective over every
    # smaller design, across every voxel count from its own to the reference's.
    for first, voxels in sorted(front, key=lambda p: (p[1], p[0])):
        if first < best and voxels < reference[1]:
            area += (best - first) * (reference[1] - voxels)
            best = first
    return area


def curve(problem, store):
    """The front's hypervolume after each evaluation."""
    reference = minimized(problem, problem["reference"])
    front, out = [], []
    for p in points(problem, store):
        if p and not any(q[0] <= p[0] and q[1] <= p[1] for q in front):
            front = [q for q in front if not (p[0] <= q[0] and p[1] <= q[1])] + [p]
        out.append(hypervolume(front, reference))
    return out


def svg(curves, evaluations):
    width, height, left, bottom, top, right = 640, 360, 70, 40, 20, 20
    top_value = max(max(c) for arm in curves.values() for c in arm) * 1.05
    x = lambda n: left + (width - left - right) * n / evaluations
    y = lambda v: height - bottom - (height - top - bottom) * v / top_value
    colors = {"nsga2": "#1f6feb", "crowding": "#d1242f"}
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" font-size="12">',
             f'<rect width="{width}" height="{height}" fill="white"/>',
             f'<line x1="{left}" y1="{height - bottom}" x2="{width - right}" y2="{height - bottom}" stroke="black"/>',
             f'<line x1="{left}" y1="{top}" x2="{left}" y2="{height - bottom}" stroke="black"/>']
    for n in range(0, evaluations + 1, evaluations // 5):
        parts.append(f'<text x="{x(n):.1f}" y="{height - bottom + 15}" text-anchor="middle">{n:,}</text>')
    # Four to eight labels on round values.
    step = 10 ** (len(str(int(top_value))) - 1)
    step = step // 2 if top_value / step < 4 else step
    for v in range(0, int(top_value) + 1, step):
        parts.append(f'<text x="{left - 6}" y="{y(v) + 4:.1f}" text-anchor="end">{v:,}</text>')
    parts.append(f'<text x="{(left + width - right) / 2}" y="{height - 6}" text-anchor="middle">evaluations</text>')
    parts.append(f'<text x="14" y="{(top + height - bottom) / 2}" text-anchor="middle" transform="rotate(-90 14 {(top + height - bottom) / 2})">hypervolume</text>')
    every = max(1, evaluations // 500)
    for i, (arm, runs) in enumerate(curves.items()):
        median = [statistics.median(c[n] for c in runs) for n in range(evaluations)]
        path = " ".join(f"{x(n + 1):.1f},{y(v):.1f}" for n, v in enumerate(median) if n % every == every - 1)
        parts.append(f'<polyline points="{path}" fill="none" stroke="{colors[arm]}" stroke-width="2"/>')
        parts.append(f'<text x="{width - right - 150}" y="{height - bottom - 20 - 16 * i}" fill="{colors[arm]}">{arm}, median of {len(runs)} seeds</text>')
    return "\n".join(parts + ["</svg>\n"])


def main():
    if len(sys.argv) < 2 or sys.argv[1] not in PROBLEMS:
        sys.exit(f"usage: front_selection.py {'|'.join(PROBLEMS)} [RESULTS_DIR]")
    problem = dict(PROBLEMS[sys.argv[1]], name=sys.argv[1])
    evaluations = problem["evaluations"]
    results = Path(sys.argv[2] if len(sys.argv) > 2 else ROOT / "target/front-selection").resolve()
    curves = {arm: [] for arm in SELECTIONS}
    print("| seed | " + " | ".join(f"{arm}: designs, hypervolume, {problem['first']}" for arm in SELECTIONS) + " |")
    for seed in SEEDS:
        cells = []
        for arm in SELECTIONS:
            store = run(problem, results, arm, seed)
            c = curve(problem, store)
            if len(c) != evaluations:
                sys.exit(f"{store}: {len(c)} evaluations, expected {evaluations}")
            curves[arm].append(c)
            with open(store.parent / "pareto.csv") as f:
                firsts = [problem["sign"] * float(line.split(",")[1]) for line in f.read().split()[1:]]
            best = problem["sign"] * min(firsts)
            cells.append(f"{len(firsts)}, {c[-1]:,.0f}, {best:.3g} {problem['unit']}")
        print(f"| {seed} | " + " | ".join(cells) + " |")
    finals = {arm: [c[-1] for c in runs] for arm, runs in curves.items()}
    wins = sum(a > b for a, b in zip(finals["nsga2"], finals["crowding"]))
    print("| median | " + " | ".join(f"{statistics.median(finals[a]):,.0f}" for a in SELECTIONS) + " |")
    print(f"NSGA-II larger on {wins} of {len(SEEDS)} seeds")
    for n in (evaluations // 5, evaluations // 2, evaluations):
        print(f"median hypervolume at {n}: " + ", ".join(
            f"{a} {statistics.median(c[n - 1] for c in curves[a]):,.0f}" for a in SELECTIONS))
    figure = ROOT / "docs/img" / f"{problem['name']}_front_hypervolume.svg"
    figure.write_text(svg(curves, evaluations))
    print(f"wrote {figure.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
