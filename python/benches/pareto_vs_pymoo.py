"""The trade-off study of docs/explanation/results.md#trade-offs: Amorph's NSGA-II against
pymoo's NSGA-II driving the same evaluator.

Question: at 6,000 evaluations of the circular arc at 6x20x6, trading RMS error against voxels,
which search keeps the larger front? Runs: seeds 1-5 of each. Measure: the hypervolume of each
run's final front against (10 %, 720 voxels), computed by pymoo's HV for both. Rule: the larger
median wins if it is also larger on at least four of the five seeds; otherwise neither does.

    python python/benches/pareto_vs_pymoo.py [SEEDS]      # from the repository's root

Needs the release coordinator (cargo build --release --bin coordinator) and the Python package
with pymoo (pip install "./python[examples]")."""

import csv
import importlib.util
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import amorph

ROOT = Path(__file__).resolve().parents[2]
RESOLUTION = "6x20x6"
EVALUATIONS = 6000

spec = importlib.util.spec_from_file_location("pymoo_pareto", ROOT / "python/examples/pymoo_pareto.py")
pymoo_pareto = importlib.util.module_from_spec(spec)
spec.loader.exec_module(pymoo_pareto)


def amorph_front(seed, results):
    start = time.perf_counter()
    subprocess.run(
        [str(ROOT / "target/release/coordinator"), "--config", str(ROOT / "configs/beam_pareto.toml"),
         "--set", f"seed={seed}", "--set", f"name=amorph_{seed}", "--set", f'results_dir="{results}"',
         "--set", f"budget.evaluations={EVALUATIONS}",
         "--set", "resolution.levels=[[6, 20, 6]]", "--set", "resolution.latest_switch=[]",
         "--set", "search.hypervolume_reference=[10.0, 720.0]", "--fresh"],
        check=True, capture_output=True)
    seconds = time.perf_counter() - start
    with open(Path(results) / f"amorph_{seed}" / "pareto.csv") as f:
        rows = list(csv.DictReader(f))
    front = [[float(r["rms"]), float(r["voxels"])] for r in rows]
    return front, seconds


def pymoo_front(seed, results):
    start = time.perf_counter()
    with amorph.Cluster(name=f"pymoo_{seed}", fresh=True, results_dir=str(results)) as cluster:
        front, _ = pymoo_pareto.optimize(cluster, 12, EVALUATIONS, seed, RESOLUTION)
    return front.tolist(), time.perf_counter() - start


def main():
    seeds = [int(s) for s in sys.argv[1:]] or [1, 2, 3, 4, 5]
    rows = []
    with tempfile.TemporaryDirectory() as results:
        for seed in seeds:
            ours, ours_s = amorph_front(seed, results)
            theirs, theirs_s = pymoo_front(seed, results)
            hv = [pymoo_pareto.hypervolume(f, RESOLUTION) for f in (ours, theirs)]
            best = [min(r for r, _ in f) for f in (ours, theirs)]
            rows.append((seed, len(ours), hv[0], best[0], ours_s, len(theirs), hv[1], best[1], theirs_s))
            print(f"seed {seed}: Amorph {len(ours)} designs, HV {hv[0]:.0f}, best {best[0]:.3f} %, "
                  f"{ours_s:.0f} s | pymoo {len(theirs)} designs, HV {hv[1]:.0f}, best {best[1]:.3f} %, "
                  f"{theirs_s:.0f} s", flush=True)
    ours = [r[2] for r in rows]
    theirs = [r[6] for r in rows]
    wins = sum(a > b for a, b in zip(ours, theirs))
    print(f"median HV: Amorph {statistics.median(ours):.0f}, pymoo {statistics.median(theirs):.0f}; "
          f"Amorph larger on {wins} of {len(rows)} seeds")


if __name__ == "__main__":
    main()
